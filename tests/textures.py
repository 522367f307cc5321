"""Synthetic floor textures and known image motions that the keypoint tests share."""

import cv2
import numpy as np


def blurred_noise(rng: np.random.Generator, size: tuple[int, int], sigmas=(1.0, 2.5, 6.0)) -> np.ndarray:
    """A floor-like texture (H, W) float, grey levels 20 to 220: uniform noise drawn from ``rng`` and blurred at each
    of ``sigmas`` (pixels), each blur weighted by its sigma, summed. ``size``: (width, height)."""
    width, height = size
    image = np.zeros((height, width))
    for sigma in sigmas:
        image += cv2.GaussianBlur(rng.uniform(-1, 1, (height, width)), (0, 0), sigma) * sigma
    return (image - image.min()) / np.ptp(image) * 200 + 20


def turned_and_shifted(image: np.ndarray, angle_deg: float, shift) -> tuple[np.ndarray, np.ndarray]:
    """``image`` turned by ``angle_deg`` about its centre and shifted by ``shift`` (px), and the 2 x 3 map of a
    point of ``image`` to where it lands (``cv2.warpAffine``'s)."""
    height, width = image.shape
    matrix = cv2.getRotationMatrix2D((width / 2, height / 2), angle_deg, 1.0)
    matrix[:, 2] += shift
    turned = cv2.warpAffine(image, matrix, (width, height), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
    return turned, matrix
