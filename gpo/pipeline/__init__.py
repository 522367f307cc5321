"""The method put together: a run config in, a trajectory out.

``schema`` (the config file's one schema: every key checked, unknown keys with "did you mean"), ``config`` (the
whole file read and written: ``OdometryConfig``, the methods from the estimators' registry), ``odometer`` (frame by
frame: the floor image, its motion, the estimator, each frame's record), ``run`` (a recording's odometry, and the
tracking camera's fusion for ``fused``) and ``propose`` (a config proposed from what a bag holds).
"""
