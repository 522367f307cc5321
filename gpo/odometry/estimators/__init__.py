"""The floor motion estimators, one module each, registered by the name a run config's ``odometry.method`` gives.

``base`` holds what every estimator is (`FloorEstimator`) and what it is given (`FloorGeometry`). A new estimator is
one module with a `FloorEstimator` subclass and one line here; the config's check of ``odometry.method`` (and so
the sweeps', which load configs) and the command line's ``--method`` read ``ESTIMATORS``.
"""

from gpo.odometry.estimators.base import FloorEstimator, FloorGeometry
from gpo.odometry.estimators.exact import ExactArc
from gpo.odometry.estimators.keypoints import RigidKeypoints
from gpo.odometry.estimators.paper import PaperGPO
from gpo.odometry.estimators.rigid import RigidFit

ESTIMATORS: dict[str, type[FloorEstimator]] = {
    estimator.NAME: estimator for estimator in (PaperGPO, ExactArc, RigidFit, RigidKeypoints)
}
"""Floor motion estimators by the name configs and the command line use, in the order the chapters present them."""

__all__ = ["ESTIMATORS", "ExactArc", "FloorEstimator", "FloorGeometry", "PaperGPO", "RigidFit", "RigidKeypoints"]
