"""Fusion: the floor odometry and a tracking camera's own odometry in one extended Kalman filter.

``ekf``: the filter (state, process model, differential updates with stochastic cloning, the camera's biases);
``settings``: a run config's ``fusion`` section; ``streaming``: the two sources' messages into the filter as they
arrive (``StreamingFusion``) or from a recording (``fuse``).
"""

from gpo.fusion.ekf import FilterDiverged, OdometryFusion, increment_covariance
from gpo.fusion.settings import FusionSettings, TrackingMount
from gpo.fusion.streaming import FusedPath, FusedPose, StreamingFusion, fuse

__all__ = [
    "FilterDiverged",
    "FusedPath",
    "FusedPose",
    "FusionSettings",
    "OdometryFusion",
    "StreamingFusion",
    "TrackingMount",
    "fuse",
    "increment_covariance",
]
