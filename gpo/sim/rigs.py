"""The two camera rigs of the simulator, like the two papers' robots.

``Rig`` and ``CameraMount`` (and their frames) are defined in ``gpo.cameras.rig``.
"""

from __future__ import annotations

import numpy as np

from gpo.cameras import T265_LIKE, Pinhole
from gpo.cameras.rig import CameraMount, Rig


def t265_rig() -> Rig:
    """The first paper's rig: a T265-like fisheye at the front of a low pallet robot.

    0.60 m ahead of the rear axle, 0.12 m above the floor, pitched 6 degrees down and rolled
    1.5 degrees, so that the floor image needs rectification. 30 frames per second.
    """
    mount = CameraMount.forward(x=0.60, y=0.0, height=0.12, pitch=np.radians(6.0), roll=np.radians(1.5))
    return Rig(
        "t265",
        T265_LIKE,
        mount,
        30.0,
        "/camera/fisheye1/image_raw",
        "/camera/fisheye1/camera_info",
        "camera_fisheye1_optical_frame",
    )


def downward_rig() -> Rig:
    """The second paper's rig: a 752 x 480 pinhole camera looking down from 0.25 m, tilted about 1 degree.

    f = 600 px with mild radial-tangential distortion, at the robot's centre, 35 frames per second.
    """
    camera = Pinhole(
        fx=600.0, fy=600.0, cx=371.5, cy=242.0, dist=(-0.12, 0.05, 4e-4, -3e-4, 0.0), width=752, height=480
    )
    mount = CameraMount.downward(x=0.0, y=0.0, height=0.25, tilt_x=np.radians(0.8), tilt_y=np.radians(-0.6))
    return Rig("downward", camera, mount, 35.0, "/camera/image_raw", "/camera/camera_info", "camera_optical_frame")


RIGS = {"t265": t265_rig, "downward": downward_rig}
