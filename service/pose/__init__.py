"""``markerflow pose``: articulated pose from per-camera OpenPose keypoints or images, by the annealed
particle filter of ``formulations.pose``; the files, the participant, the frame loop and the output."""
