"""A frame's brightness levelled for Lucas-Kanade, which assumes that a patch keeps its brightness from frame to frame.

A few per cent of exposure flicker on a low-contrast floor pulls every track off, and a brightness gradient fixed to
the camera (vignetting, the robot's own light) pulls each track towards standing still by an amount that varies
across the image. ``levelled`` divides an image by its local mean (a flat field) and scales it to one mean and
contrast; the floor image's KLT flow (``gpo.motion.klt``) and the keypoints followed between keyframes
(``gpo.motion.following``) track levelled images.
"""

from __future__ import annotations

import cv2
import numpy as np

GREY_MEAN, GREY_SPREAD = 128.0, 40.0  # every levelled image is scaled to this mean and standard deviation


STATISTICS_STEP = 2  # image statistics are taken over every second row and column


def levelled(image: np.ndarray, local_mean: np.ndarray | None = None, valid: np.ndarray | None = None) -> np.ndarray:
    """``image`` (H, W) float32 divided by its ``local_mean`` (H, W) float32 (a flat field; None: not) and scaled to
    the mean ``GREY_MEAN`` and the standard deviation ``GREY_SPREAD`` over the pixels ``valid`` (uint8, nonzero; None:
    all), as uint8: the brightness Lucas-Kanade sees, whatever the exposure."""
    sample = np.s_[::STATISTICS_STEP, ::STATISTICS_STEP]  # a quarter of the pixels: plenty for mean and spread
    mask = None if valid is None else valid[sample]
    if local_mean is not None:
        image = cv2.divide(image, local_mean)  # where the local mean is 0, so is the image: 0
    mean, spread = (float(v[0, 0]) for v in cv2.meanStdDev(image[sample], mask=mask))
    gain = GREY_SPREAD / max(spread, 1e-6)
    return cv2.convertScaleAbs(image, alpha=gain, beta=GREY_MEAN - gain * mean)


def reduced_local_mean(image: np.ndarray, size: int, reduction: int) -> np.ndarray:
    """The local mean of ``image`` (H, W) float32 over a box of about ``size`` pixels, taken on the image reduced
    ``reduction`` times (each reduced pixel the mean of its block) and enlarged back bilinearly: a smooth flat field
    for a fraction of the full box filter's cost (the box of ``size / reduction`` reduced pixels, at least 1)."""
    height, width = image.shape
    small = cv2.resize(image, (max(1, round(width / reduction)), max(1, round(height / reduction))),
                       interpolation=cv2.INTER_AREA)
    box = max(1, round(size / reduction))
    return cv2.resize(cv2.blur(small, (box, box)), (width, height), interpolation=cv2.INTER_LINEAR)
