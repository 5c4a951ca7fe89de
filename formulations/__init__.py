"""The mathematics of markerflow: window problems, their formulations, markers and cameras."""
