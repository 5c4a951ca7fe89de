"""Calibrated cameras (OpenCV conventions), the stacked rig, triangulation, and the two camera association modes."""
