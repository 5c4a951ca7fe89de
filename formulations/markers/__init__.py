"""Markers over time: the marker state carried between windows, rigid alignment, the guide track and cloud candidates."""
