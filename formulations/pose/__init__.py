"""Articulated pose by annealed particle filtering (Davison, Deutscher & Reid 2001, Sections 3-4).

A body is a tree of rigid segments joined by sockets (3 DOF), saddles (2) and hinges (1) under a
6-DOF root, with joint range limits and truncated cones for flesh (``body``, ``kinematics``,
``human``, ``from_subject``). A pose is a configuration vector X; the annealed particle filter
(``apf``) searches for the X that maximises a weighting function w(X, Z) = exp(-E(X, Z)), layer
by layer, and ``tracker`` runs it frame after frame. The measurements are energies E summed over
cameras as eq. 5: edges and foreground (``silhouette`` over ``image_maps``), 2D keypoints
(``keypoints``) and markers (``markers``). After the APF, ``refine`` polishes an estimate by a
bounded local least-squares solve on a measurement's residuals (keypoints), inside the joint limits.
"""
