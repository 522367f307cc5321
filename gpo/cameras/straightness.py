"""Check a camera model on a real image: straight lines in space must unproject onto planes.

Points on a straight line in space and the camera's centre span a plane, so the rays of their
pixels, unprojected through a correct camera model, all lie in one plane through the centre. The
angle between each ray and the best such plane (the smallest singular vector of the stacked unit
rays) measures how wrong the model is, in degrees, with no target geometry needed beyond
straightness. The lines come from an AprilGrid (Kalibr's and Basalt's calibration target): the
edges of each row and column of tags are straight.
"""

from __future__ import annotations

import cv2
import numpy as np

from gpo.cameras.base import CameraModel


def plane_residuals_deg(rays: np.ndarray) -> np.ndarray:
    """Angles (degrees, (N,)) between unit rays (N, 3) and the plane through the origin that fits them best."""
    if len(rays) < 3:
        raise ValueError(f"a plane through the centre needs at least 3 rays, got {len(rays)}")
    normal = np.linalg.svd(rays)[2][-1]
    return np.degrees(np.arcsin(np.clip(np.abs(rays @ normal), 0.0, 1.0)))


def aprilgrid_tags(image: np.ndarray, border_bits: int = 2) -> dict[int, np.ndarray]:
    """AprilTag 36h11 tags found in a grey uint8 ``image``: id -> corners (4, 2) in pixels.

    Kalibr's AprilGrid prints its tags with a black border two bits wide. The corners are in
    OpenCV's order (clockwise from the tag's own top-left) and refined to sub-pixel.
    """
    parameters = cv2.aruco.DetectorParameters()
    parameters.markerBorderBits = border_bits
    parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    parameters.adaptiveThreshWinSizeMin = 3
    parameters.adaptiveThreshConstant = 7
    detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11), parameters)
    corners, ids, _ = detector.detectMarkers(image)
    if ids is None:
        return {}
    return {int(i): c.reshape(4, 2).astype(np.float64) for i, c in zip(ids.ravel(), corners, strict=True)}


def aprilgrid_lines(tags: dict[int, np.ndarray], tag_cols: int) -> list[np.ndarray]:
    """Pixels (M, 2) along each straight edge of a row or a column of tags, where at least two tags were found.

    Tag ``id`` sits in row ``id // tag_cols`` and column ``id % tag_cols`` of the grid; a row's tags
    share their top edge (corners 0, 1) and their bottom edge (3, 2), a column's its left (0, 3)
    and right (1, 2) edges.
    """
    lines = []
    for group_of, edges in ((lambda i: i // tag_cols, ((0, 1), (3, 2))), (lambda i: i % tag_cols, ((0, 3), (1, 2)))):
        groups: dict[int, list[np.ndarray]] = {}
        for tag_id, corners in tags.items():
            groups.setdefault(group_of(tag_id), []).append(corners)
        for members in groups.values():
            if len(members) >= 2:
                lines.extend(np.concatenate([corners[list(edge)] for corners in members]) for edge in edges)
    return lines


def line_residuals_deg(camera: CameraModel, lines: list[np.ndarray]) -> np.ndarray:
    """The plane residuals (degrees) of every point of every line, unprojected through ``camera``."""
    residuals = []
    for pixels in lines:
        rays, valid = camera.unproject(pixels)
        if not valid.all():
            raise ValueError(f"{int((~valid).sum())} line points have no ray in this camera model")
        residuals.append(plane_residuals_deg(rays))
    return np.concatenate(residuals)
