"""``joint-3d`` association: detections matched across cameras into 3D points, whose resources are their detections."""
