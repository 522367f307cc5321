"""A camera on a robot: what the camera is, where it sits, and the names it is recorded under.

Frames (REP-103/105): ``base_link`` at the rear-axle centre on the floor, x forward, y left,
z up; the camera optical frame x right, y down, z forward. A ``CameraMount`` is the pose of the
optical frame in ``base_link``. The tracking camera's body frame (x forward, y left, z up, as the
T265 reports its pose) is the optical frame turned by ``OPTICAL_IN_BODY``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from gpo.cameras.files import Camera

# columns: the optical x (right), y (down), z (forward) axes written in a forward-looking body frame
OPTICAL_IN_BODY = Rotation.from_matrix([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


@dataclass(frozen=True, eq=False)
class CameraMount:
    """Pose of the camera optical frame in ``base_link``: ``position`` (3,) metres, ``rotation`` base <- optical."""

    position: np.ndarray
    rotation: Rotation

    @classmethod
    def forward(cls, x: float, y: float, height: float, pitch: float = 0.0, roll: float = 0.0) -> CameraMount:
        """A forward-looking camera ``height`` metres above the floor at (x, y) in ``base_link``.

        ``pitch`` (radians, about the camera's left axis, positive looks down) and ``roll``
        (radians, about its forward axis, positive lifts its left side) tilt it away from level.
        """
        body = Rotation.from_euler("YX", [pitch, roll])
        return cls(np.array([x, y, height], dtype=float), body * OPTICAL_IN_BODY)

    @classmethod
    def downward(cls, x: float, y: float, height: float, tilt_x: float = 0.0, tilt_y: float = 0.0) -> CameraMount:
        """A camera looking straight down from ``height`` metres, image top towards the robot's front.

        ``tilt_x`` and ``tilt_y`` (radians) turn it about base_link's x and y axes.
        """
        # optical x = -y_base (image right = robot right), y = -x_base (image down = backwards), z = -z_base
        down = Rotation.from_matrix([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
        return cls(np.array([x, y, height], dtype=float), Rotation.from_euler("xy", [tilt_x, tilt_y]) * down)

    @classmethod
    def from_rpy(cls, position, roll: float, pitch: float, yaw: float) -> CameraMount:
        """A camera whose body frame (x forward, y left, z up) sits at ``position`` (3,) metres in ``base_link``,
        turned by ``roll``, ``pitch`` and ``yaw`` (radians, REP-103: fixed axes x, y, z, i.e. R = Rz(yaw) Ry(pitch)
        Rx(roll)); positive pitch looks down, positive roll lifts the camera's left side."""
        body = Rotation.from_euler("ZYX", [yaw, pitch, roll])
        return cls(np.asarray(position, dtype=float), body * OPTICAL_IN_BODY)

    @property
    def body_rpy(self) -> tuple[float, float, float]:
        """(roll, pitch, yaw) of the camera's body frame in ``base_link``, radians, as ``from_rpy`` takes them."""
        yaw, pitch, roll = self.body_rotation.as_euler("ZYX")
        return float(roll), float(pitch), float(yaw)

    @property
    def height(self) -> float:
        """Height of the optical centre above the floor, metres."""
        return float(self.position[2])

    @property
    def body_rotation(self) -> Rotation:
        """base <- camera body frame (x forward, y left, z up), as a tracking camera reports its pose."""
        return self.rotation * OPTICAL_IN_BODY.inv()

    def to_camera(self, points_base) -> np.ndarray:
        """Points (..., 3) of base_link, metres, in the optical frame (x right, y down, z forward)."""
        points = np.asarray(points_base, dtype=float) - self.position
        return self.rotation.inv().apply(points.reshape(-1, 3)).reshape(points.shape)


@dataclass(frozen=True, eq=False)
class Rig:
    """A camera on a robot: the model, the mount, the frame rate and the names it is recorded under."""

    name: str
    camera: Camera  # any model of gpo.cameras
    mount: CameraMount
    rate_hz: float
    image_topic: str
    info_topic: str
    frame_id: str


def rays_in_base(rig: Rig, pixels) -> tuple[np.ndarray, np.ndarray]:
    """Unit rays (..., 3) in ``base_link`` of the rig's ``pixels`` (..., 2), and their validity (...)."""
    rays, valid = rig.camera.unproject(pixels)
    return rig.mount.rotation.apply(rays.reshape(-1, 3)).reshape(rays.shape), valid


def floor_points(rig: Rig, rays_base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where rays (..., 3) from the camera in ``base_link`` meet the floor z = 0: (x, y) (..., 2) metres, NaN
    where a ray does not point down, and that mask (...)."""
    origin = rig.mount.position
    hits = rays_base[..., 2] < -1e-9
    with np.errstate(invalid="ignore", divide="ignore"):
        reach = np.where(hits, -origin[2] / rays_base[..., 2], np.nan)
    return origin[:2] + reach[..., None] * rays_base[..., :2], hits
