"""``per-camera`` association: every marker tracked in every camera image by the window LP, then located across cameras."""
