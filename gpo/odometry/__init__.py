"""Stage 3 of the method: from the floor's motion to the robot's. ``kinematics`` (scale, the first paper's bicycle
model as printed, exact SE(2) arcs, composition) and ``estimators`` (the floor motion estimators, one plug-in each)."""
