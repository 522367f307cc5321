"""Floor outages: stretches of a recording where the floor cannot be measured, as effects on rendered frames.

A real robot loses its view of the floor for a second or two now and then. Each kind (``KINDS``) is an image
effect applied to the frames rendered inside an ``Outage``'s interval, so the renderer itself stays as it is:

- ``textureless``: a featureless patch of floor (paint, a rubber mat): the frame smoothed to its local mean;
- ``glare``: a bright reflection covering the patch: the frame washed out to near white, its contrast a twentieth;
- ``fast``: motion too fast for the exposure and the pyramid: the frame smeared along the direction of travel
  (image rows, the floor's motion in the fisheye's lower half) over ``FAST_SMEAR_PX`` pixels;
- ``lifted``: the robot's front lifted off the floor (a bump, a ramp's lip): the floor out of focus and in shadow.

Each leaves too little local contrast, or too few trackable corners, for the floor flow (``gpo.motion.klt``), which
flags the frames; none changes the motion, the ground truth or the tracking camera.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

KINDS = ("textureless", "glare", "fast", "lifted")
FAST_SMEAR_PX = 121


@dataclass(frozen=True)
class Outage:
    """The floor unmeasurable for ``duration_s`` seconds from ``start_s`` (seconds since the recording's start),
    for the reason ``kind`` (one of ``KINDS``)."""

    kind: str
    start_s: float
    duration_s: float

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"unknown outage kind {self.kind!r}; the kinds are {', '.join(KINDS)}")
        if not (self.start_s >= 0 and self.duration_s > 0):
            raise ValueError(f"an outage needs start_s >= 0 and duration_s > 0, got {self.start_s}, {self.duration_s}")

    def covers(self, time_s: float) -> bool:
        return self.start_s <= time_s < self.start_s + self.duration_s


def outage_at(outages, time_s: float) -> Outage | None:
    """The outage of ``outages`` covering ``time_s`` (seconds), or None."""
    return next((outage for outage in outages if outage.covers(time_s)), None)


def apply_outage(kind: str, image: np.ndarray) -> np.ndarray:
    """``image`` (H, W) uint8 as the camera sees the floor during an outage of ``kind``."""
    if kind == "textureless":
        return cv2.GaussianBlur(image, (0, 0), 40.0)
    if kind == "glare":
        return (255.0 - (255.0 - image.astype(np.float32)) / 20.0).astype(np.uint8)
    if kind == "fast":
        return cv2.blur(image, (1, FAST_SMEAR_PX))
    if kind == "lifted":
        return (0.5 * cv2.GaussianBlur(image, (0, 0), 15.0)).astype(np.uint8)
    raise ValueError(f"unknown outage kind {kind!r}; the kinds are {', '.join(KINDS)}")


def outage_fraction(outages, frame_times_s: np.ndarray) -> float:
    """The share of ``frame_times_s`` (seconds) inside one of ``outages``."""
    return float(np.mean([outage_at(outages, t) is not None for t in frame_times_s]))
