"""Stage 3 of the method: from the floors motion to the robots (kinematics) and the estimators that do it."""
