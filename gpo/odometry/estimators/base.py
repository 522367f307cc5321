"""A floor motion estimator: the plug-in behind each ``odometry.method`` of a run config.

An estimator turns a measured floor motion into the robot's increment over the time it spans (one frame, or from a
keyframe to the latest frame for an estimator that reads ``KEYFRAMES``): (dx, dy, dtheta), base_link at the latest
frame in base_link at the first, metres and radians (REP-103: x forward, y left, z up; dtheta positive
counter-clockwise). It reads one kind of measurement (``MOTION``): ``tracks``, the floor image's
KLT flow (``gpo.motion.klt.FlowMeasurement``), or ``keypoints``, matched keypoints
(``gpo.motion.keypoints.FeatureMatches``); where those pixels lie on the floor is its ``FloorGeometry``.

A new estimator is one module of ``gpo.odometry.estimators`` holding a subclass of `FloorEstimator`, and one line in
``gpo.odometry.estimators.ESTIMATORS``, which the config's check of its method, the command line's ``--method``
and so the sweeps read.
"""

from __future__ import annotations

import functools
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

import cv2
import numpy as np

from gpo.cameras import CameraModel
from gpo.cameras.rig import CameraMount
from gpo.floor_image.analytic import PixelsOnFloor
from gpo.floor_image.image import FloorImage
from gpo.motion.median import median_of


@dataclass(frozen=True, eq=False)
class FloorGeometry:
    """Where the pixels an estimator reads lie on the floor, in base_link (metres).

    For a floor image (``floor``): its affine map (``FloorImage.affine``); ``nadir_px`` is its pixel straight below
    the camera. For keypoints detected in the camera's own image (the ``keypoints`` route, ``floor`` None): the
    ``camera`` model and its ``mount``, each pixel's ray followed down to the floor (``pixels_to_floor``, once per
    pixel of the image: ``PixelsOnFloor``).
    """

    floor: FloorImage | None
    camera: CameraModel
    mount: CameraMount

    @functools.cached_property
    def nadir_px(self) -> np.ndarray:
        """The floor image's pixel (u, v) straight below the camera."""
        affine = self.floor.affine
        return np.linalg.solve(affine[:, :2], self.mount.position[:2] - affine[:, 2])

    @functools.cached_property
    def _to_metres(self) -> tuple[np.ndarray, np.ndarray]:
        """The floor image's affine map as (matrix, offset): pixels (N, 2) @ matrix + offset are metres."""
        affine = self.floor.affine
        return affine[:, :2].T.copy(), affine[:, 2].copy()

    @property
    def pixel_m(self) -> float:
        """About how far on the floor one pixel reaches, metres."""
        if self.floor is not None:
            return self.floor.metres_per_pixel
        return self.mount.height / self.camera.fx

    def metres(self, uv: np.ndarray) -> np.ndarray:
        """Floor-image pixels (N, 2) as floor points (N, 2) of base_link."""
        matrix, offset = self._to_metres
        return uv @ matrix + offset

    def vector_metres(self, vector: np.ndarray) -> np.ndarray:
        """A displacement (2,) in floor-image pixels as one in base_link, metres."""
        return self._to_metres[0].T @ vector

    @functools.cached_property
    def _pixels_on_floor(self) -> PixelsOnFloor:
        """The camera's pixels put on the floor once (``gpo.floor_image.analytic.PixelsOnFloor``)."""
        return PixelsOnFloor.of(self.camera, self.mount)

    def on_floor(self, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixels (N, 2) as floor points (N, 2) of base_link (metres), and which of them reach the floor (N,): through
        the floor image's affine map, or for the camera's own pixels its table of them on the floor."""
        if self.floor is not None:
            return self.metres(pixels), np.ones(len(pixels), dtype=bool)
        return self._pixels_on_floor(pixels)


class FloorEstimator(ABC):
    """One frame's floor motion in, the robot's increment out.

    ``NAME``: the method's name in configs and on the command line. ``MOTION``: the measurement it reads (``tracks``
    or ``keypoints``). ``KEYFRAMES``: whether it reads a measurement from a keyframe several frames back as well as
    one from the previous frame (the config's ``keyframe`` policy, ``gpo.motion.keyframes``), or only the latter.
    ``OVERVIEW``: whether the KLT flow it reads is checked on a wider view of the floor (``gpo.motion.overview``: the
    suite's estimators, not the paper's). Made once per run from the run's ``config`` (a
    ``gpo.pipeline.config.OdometryConfig``, which the method's later stage defines: an estimator reads the sections it
    needs, e.g. ``vector``, ``model``, ``features``) and the ``geometry`` of what it measures.
    """

    NAME: ClassVar[str]
    MOTION: ClassVar[str] = "tracks"
    OVERVIEW: ClassVar[bool] = False  # whether its tracks are checked on a wider view (``gpo.motion.overview``)
    KEYFRAMES: ClassVar[bool] = False

    def __init__(self, config: Any, geometry: FloorGeometry):
        self.config = config
        self.geometry = geometry

    @abstractmethod
    def increment(self, measurement, dt: float) -> tuple[np.ndarray | None, str | None]:
        """The increment (dx, dy, dtheta) over the time the measurement spans, from the frame its starts lie in (the
        previous frame, or for a ``KEYFRAMES`` estimator the keyframe) to the latest, or None and the reason why the
        measurement gives none; ``dt`` is that time, seconds."""


def vector_motion(
    measurement, geometry: FloorGeometry, statistic: str, tracks: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The floor point a motion vector measures (the median start of the kept tracks, or of those the mask ``tracks``
    picks) and its displacement by the ``statistic`` (``median`` or ``mean``) of their vectors, both in base_link,
    metres."""
    starts, vectors = measurement.start, measurement.vectors
    if tracks is not None:
        starts, vectors = starts[tracks], vectors[tracks]
    middle = median_of if statistic == "median" else np.mean
    return geometry.metres(median_of(starts, axis=0)), geometry.vector_metres(middle(vectors, axis=0))


def agreeing(start_m: np.ndarray, end_m: np.ndarray, threshold_m: float) -> np.ndarray | None:
    """Which pairs of ``start_m`` and ``end_m`` (N, 2), metres, agree on one rigid motion of the floor: the inliers
    (N,) of a RANSAC fit of a rotation, translation and scale, each landing within ``threshold_m`` of where the
    fit puts it; None when no fit is found. A few gross mismatches (a keypoint matched to another's twin, 100 px
    off) pull a least-squares fit by degrees; RANSAC leaves them out."""
    _, inliers = cv2.estimateAffinePartial2D(
        start_m, end_m, method=cv2.RANSAC, ransacReprojThreshold=threshold_m, maxIters=200, confidence=0.995
    )
    return None if inliers is None else inliers.ravel().astype(bool)
