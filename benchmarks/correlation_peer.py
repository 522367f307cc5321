"""The floor odometer a user might write instead of gpo, as a peer for the benchmarks: OpenCV only.

    python benchmarks/correlation_peer.py BAG CONFIG

The fisheye's floor patch mapped to a metric top view (gpo's own floor image of the config, its region widened
``WIDEN`` times about its centre at as many times the metres per pixel, so the same pixels see more floor), phase
correlation (``cv2.phaseCorrelate``, Hanning-windowed) between consecutive views for the patch's shift, and the
no-slip constraint of a car-like robot: base_link (the rear axle's centre) moves along its own x only. A floor point
p = (x_c, y_c) in base_link, seen again after the robot moved s along x and turned theta, lies at
p' = R(-theta) (p - (s, 0)) ~ p - (s, 0) - theta (-y_c, x_c), so the patch's shift d = p' - p gives
theta = -d_y / x_c and s = -d_x + theta * y_c. Nothing is flagged and nothing is tuned per recording.

Printed: the final position error in % of the distance and the final heading error against the recording's truth.
"""

from __future__ import annotations

import argparse
import math

import cv2
import numpy as np

from gpo.io.bag import Recording
from gpo.io.trajectory import Trajectory
from gpo.metrics import final_error
from gpo.odometry.kinematics import compose
from gpo.pipeline.config import OdometryConfig, load_config
from gpo.pipeline.odometer import FloorOdometer
from gpo.sim.record import GROUND_TRUTH_TOPIC

WIDEN = 2.0  # the peer's top view covers this many times the config's floor region, on as many pixels


def peer_config(config: OdometryConfig) -> OdometryConfig:
    """``config`` with its floor image's region widened ``WIDEN`` times about its centre, on as many pixels."""
    return config.replace(floor=config.floor.widened(WIDEN))


def correlation_odometry(bag, config: OdometryConfig) -> Trajectory:
    """base_link in odom at every camera frame of ``bag``, by phase correlation and no slip (see the module)."""
    config = peer_config(config)
    odometer = FloorOdometer(config)
    affine, width, height = config.floor.affine, config.floor.width, config.floor.height
    window = cv2.createHanningWindow((width, height), cv2.CV_32F)
    centre = affine @ np.array([(width - 1) / 2, (height - 1) / 2, 1.0])
    stamps, poses = [], [np.zeros(3)]
    previous = None
    with Recording(bag) as recording:
        for frame in recording.frames(config.rig.image_topic, gray=True, progress=False):
            view = odometer.floor_image(frame.image).astype(np.float32)
            stamps.append(frame.stamp_ns)
            if previous is not None:
                (du, dv), _ = cv2.phaseCorrelate(previous, view, window)
                dx, dy = affine[:, :2] @ np.array([du, dv])  # the patch's shift, metres in base_link
                theta = -dy / centre[0]
                step = -dx + theta * centre[1]
                poses.append(compose(poses[-1], np.array([step, 0.0, theta])))
            previous = view
    poses = np.array(poses)
    return Trajectory.from_planar(np.array(stamps, np.int64), poses[:, 0], poses[:, 1], poses[:, 2], frame_id="odom")


def peer_error(bag, config: OdometryConfig) -> dict:
    """The peer's final position error (% of the distance) and heading error (degrees) on ``bag``."""
    estimate = correlation_odometry(bag, config)
    with Recording(bag) as recording:
        truth = recording.trajectory(GROUND_TRUTH_TOPIC)
    error = final_error(estimate, truth)
    return {"final_error_percent": float(error.percent), "final_heading_deg": math.degrees(error.heading_rad)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("bag")
    parser.add_argument("config")
    args = parser.parse_args()
    error = peer_error(args.bag, load_config(args.config))
    percent, heading = error["final_error_percent"], error["final_heading_deg"]
    print(f"correlation peer: final error {percent:.3f} %, heading {heading:+.2f} deg")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
