"""Files in and out: labeled recordings (C3D, TRC, CSV), camera calibrations, stored windows."""
