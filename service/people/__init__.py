"""People seen by several calibrated video cameras as 2D body keypoints (OpenPose), as boxes."""
