"""Fisheye to cubemap: five virtual 90-degree pinhole cameras around the fisheye's optical centre.

A fisheye bends straight lines; a pinhole camera keeps them straight. The cubemap turns one
wide-angle fisheye frame into five pinhole images, the faces of a cube centred on the lens: front,
left, right, bottom and top (the back face sees nothing of a forward lens and is left out).

Frames and units
----------------
The fisheye optical frame (REP-103): x right, y down, z forward. Each face is a pinhole optical
frame of its own (x right, y down, z along the face's viewing direction); ``Face.rotation`` turns
face-frame vectors into the fisheye frame (fisheye_optical <- face). Pixels are (u, v), u right,
v down, the centre of the top-left pixel at (0, 0), as in ``gpo.cameras`` and OpenCV.

Face rotations: the first paper's eqs. 8-12
-------------------------------------------
The paper writes X_C = R_Face X_CI (eq. 14): R_Face takes a face's coordinates to the cubemap model's, the
fisheye frame here (fisheye_optical <- face). The paper's web text lists each matrix's nine entries in one run::

    (8)  R_Front  : 1 0 0,  0 1 0,  0 0 1
    (9)  R_Left   : 0 0 1,  0 1 0, -1 0 0
    (10) R_Right  : 0 0 -1, 0 1 0,  1 0 0
    (11) R_Bottom : 1 0 0,  0 0 -1, 0 1 0
    (12) R_Top    : 1 0 0,  0 0 1,  0 -1 0

The same text lists eq. 7's K as "fx 0 0, 0 fy 0, cx cy 1" and eq. 21's H as "h11 h21 h31, h12 h22 h32,
h13 h23 1": column by column. Read the same way, eqs. 8-12 are exactly the matrices used here, with
R_x(t), R_y(t) the rotations by t about the fisheye's x (right) and y (down) axes::

    (8)  R_front  = I
    (9)  R_left   = R_y(-90 deg) = [[0, 0, -1], [0, 1, 0], [ 1, 0, 0]]
    (10) R_right  = R_y(+90 deg) = [[0, 0,  1], [0, 1, 0], [-1, 0, 0]]
    (11) R_bottom = R_x(-90 deg) = [[1, 0, 0], [0, 0,  1], [0, -1, 0]]
    (12) R_top    = R_x(+90 deg) = [[1, 0, 0], [0, 0, -1], [0,  1, 0]]

Read row by row instead, eqs. 9-12 are the transposes of these: the printed R_Left would be this R_right,
and the printed R_Bottom this R_top, which turns the face's axis (0, 0, 1) to (0, -1, 0), up in the optical
frame (y down), so a face named bottom would see the ceiling. The package takes the column reading because
under it every face looks where its name says (``tests/test_paper_equations.py`` shows both readings).

The third column of each matrix is the face's viewing direction in the fisheye frame: left (-x),
right (+x), bottom (+y, down: the floor for a forward-looking camera) and top (-y). Every face keeps
the edge it shares with the front face towards the front face, so the five faces unfold into a
cross (``CROSS_CELLS``) whose seams are continuous: the bottom face's top rows look forward, the
top face's bottom rows look forward, the left and right faces' image-down is the fisheye's down.

One intrinsic matrix for all faces
----------------------------------
A face of N x N pixels has f = N / 2 and c = (N - 1) / 2::

    K = [[N/2, 0, (N-1)/2], [0, N/2, (N-1)/2], [0, 0, 1]]

so its outer pixel edges (-0.5 and N - 0.5) lie at tan = +-1: the face spans exactly 90 degrees
and neighbouring faces meet edge to edge. The paper makes a face half the cubemap's resolution; the
rule used here is N = 2 round(f_fisheye) with f_fisheye = (fx + fy) / 2, so that the face's focal
length N/2 is the fisheye's: at its centre the front face is exactly as dense (pixels per unit of
tangent) as the fisheye at its principal point, and no face throws detail away. N = 572 pixels for
the T265-like camera (f = 286 px); pass ``face_size`` to choose another.

EUCM to cubemap: the first paper's eqs. 13-18, then its eqs. 6-7
----------------------------------------------------------------
As printed, in the fisheye's optical frame (x right, y down, z forward)::

    (13) X_CI = (u, v, 1)                                  a pixel of face F
    (14) X_C  = R_Face X_CI
    (15) X_C  = (x_C, y_C, z_C)
    (16) rho  = sqrt(beta (x_C^2 + y_C^2) + z_C^2)
    (17) x_P  = x_C / (alpha rho + (1 - alpha) z_C)
    (18) y_P  = y_C / (alpha rho + (1 - alpha) z_C)
    (6)  X_M  = (x_P, y_P, 1)
    (7)  X_I  = K X_M = (u_f, v_f, 1),  K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]   the fisheye pixel

The package differs in one place: eq. 13 here is X_CI = K_face^-1 (u, v, 1), the ray of the face pixel.
A rotation turns directions, and (u, v, 1) in pixels is a direction only once the face's own intrinsics
(the paper's f_Face, c_Face: the section above) are taken off; the paper's text calibrates those intrinsics but its
eq. 13 leaves them implicit. The package also marks where the fisheye sees nothing: a face pixel is valid
where z_C > -w rho (the EUCM's valid region, ``gpo.cameras.EUCM``) and (u_f, v_f) lies inside the image.

Eqs. 15-18 with 6-7 are ``camera.project`` of ``gpo.cameras``, so any camera model of that module works.
These look-up tables are computed once per (camera, face size) and applied with ``cv2.remap``.
Face pixels that are not valid are masked: ``maps`` holds NaN there and ``face_image`` the border
value, never a colour copied from the edge of the fisheye image.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import NamedTuple

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from gpo.cameras import CameraModel, Pinhole

FACE_NAMES = ("front", "left", "right", "bottom", "top")
FACE_ROTATIONS = {
    "front": Rotation.identity(),
    "left": Rotation.from_euler("y", -90.0, degrees=True),
    "right": Rotation.from_euler("y", 90.0, degrees=True),
    "bottom": Rotation.from_euler("x", -90.0, degrees=True),
    "top": Rotation.from_euler("x", 90.0, degrees=True),
}
"""fisheye_optical <- face: the first paper's eqs. 8-12 read column by column (the module docstring)."""

CROSS_CELLS = {"top": (0, 1), "left": (1, 0), "front": (1, 1), "right": (1, 2), "bottom": (2, 1)}
"""(row, column) of each face in the 3 x 3 cross drawn by ``Cubemap.cross``."""

MIN_FACE_SIZE = 8
SEAM_TOLERANCE_PX = 1e-9  # a face holds points this close outside its square, so rounding opens no crack on a seam
_OUTSIDE = -16.0  # remap coordinate of a masked pixel: far enough outside that only the border value is read


def default_face_size(camera: CameraModel) -> int:
    """Face size N = 2 round((fx + fy) / 2) pixels: the face's centre as dense as the fisheye's (N/2 = f)."""
    return 2 * round((camera.fx + camera.fy) / 2.0)


@dataclass(frozen=True, eq=False)
class Face:
    """One face of the cubemap: a ``size`` x ``size`` pinhole camera turned by ``rotation`` (fisheye <- face).

    The face holds the closed square [-0.5, size - 0.5]^2 of its pixels' area, widened by
    ``SEAM_TOLERANCE_PX``: a direction on the seam of two faces belongs to both, so every direction the
    five faces look at lands on at least one of them.
    """

    name: str
    rotation: Rotation
    size: int

    @functools.cached_property
    def pinhole(self) -> Pinhole:
        """The face as an undistorted ``gpo.cameras.Pinhole``: f = size / 2, c = (size - 1) / 2 pixels."""
        focal, centre = self.size / 2.0, (self.size - 1) / 2.0
        return Pinhole(focal, focal, centre, centre, (0.0, 0.0, 0.0, 0.0), self.size, self.size)

    @property
    def K(self) -> np.ndarray:
        """The 3 x 3 intrinsic matrix, the same for every face of a cubemap."""
        return self.pinhole.camera_matrix

    def contains(self, uv) -> np.ndarray:
        """True (...) where face pixels ``uv (..., 2)`` lie on the face's closed square (see the class)."""
        uv = np.asarray(uv, dtype=np.float64)
        if uv.ndim == 0 or uv.shape[-1] != 2:
            raise ValueError(f"pixels must have shape (..., 2), got shape {uv.shape}")
        low, high = -0.5 - SEAM_TOLERANCE_PX, self.size - 0.5 + SEAM_TOLERANCE_PX
        with np.errstate(invalid="ignore"):
            return np.all((uv >= low) & (uv <= high), axis=-1)

    def rays(self, uv) -> tuple[np.ndarray, np.ndarray]:
        """Unit rays (..., 3) in the fisheye frame of face pixels ``uv (..., 2)`` (eqs. 13-14, with K^-1); valid
        (...) where ``uv`` lies on the face, NaN elsewhere."""
        pinhole = self.pinhole
        valid = self.contains(uv)
        # K^-1 (u, v, 1) = (x, y, 1)
        normalised = (np.asarray(uv, dtype=np.float64) - [pinhole.cx, pinhole.cy]) / [pinhole.fx, pinhole.fy]
        rays = np.concatenate([normalised, np.ones_like(normalised[..., :1])], axis=-1)
        rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
        rays[~valid] = np.nan
        return _rotate(self.rotation, rays), valid

    def pixels(self, rays) -> tuple[np.ndarray, np.ndarray]:
        """Face pixels (..., 2) of fisheye-frame rays (..., 3); valid (...) where the ray meets the face, else NaN."""
        uv, valid = self.pinhole.project(_rotate(self.rotation.inv(), rays))
        valid &= self.contains(uv)
        uv[~valid] = np.nan
        return uv, valid


class FaceMaps(NamedTuple):
    """Look-up tables of one face: fisheye pixel (map_x, map_y), float32 (N, N), NaN where ``valid`` is False."""

    map_x: np.ndarray
    map_y: np.ndarray
    valid: np.ndarray


class Cubemap:
    """The five faces of a cubemap around ``camera``'s optical centre, with their look-up tables.

    ``face_size`` (pixels, >= 8) defaults to ``default_face_size(camera)``.
    """

    def __init__(self, camera: CameraModel, face_size: int | None = None):
        size = default_face_size(camera) if face_size is None else face_size
        if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < MIN_FACE_SIZE:
            raise ValueError(f"face_size must be a whole number of pixels >= {MIN_FACE_SIZE}, got {face_size!r}")
        self.camera = camera
        self.face_size = int(size)
        self.faces = {name: Face(name, FACE_ROTATIONS[name], self.face_size) for name in FACE_NAMES}

    def face(self, name: str) -> Face:
        """The face called ``name``; a ValueError listing the faces otherwise."""
        if name not in self.faces:
            raise ValueError(f"unknown face {name!r}; the faces are {', '.join(FACE_NAMES)}")
        return self.faces[name]

    def face_to_fisheye(self, name: str, uv) -> tuple[np.ndarray, np.ndarray]:
        """Fisheye pixels (..., 2) shown at face pixels ``uv (..., 2)`` (eqs. 13-18), and their validity (...).

        Valid where ``uv`` lies on the face and its ray projects into the fisheye image; NaN elsewhere.
        """
        rays, on_face = self.face(name).rays(uv)
        fisheye_uv, valid = self.camera.project(rays)
        valid &= on_face & self.camera.in_image(fisheye_uv)
        fisheye_uv[~valid] = np.nan
        return fisheye_uv, valid

    def fisheye_to_face(self, name: str, uv) -> tuple[np.ndarray, np.ndarray]:
        """Face pixels (..., 2) where fisheye pixels ``uv (..., 2)`` appear on face ``name``, and their validity.

        Valid where ``uv`` lies in the fisheye image, has a ray, and that ray meets the face; NaN elsewhere.
        """
        face = self.face(name)
        rays, valid = self.camera.unproject(uv)
        face_uv, on_face = face.pixels(rays)
        valid &= on_face & self.camera.in_image(uv)
        face_uv[~valid] = np.nan
        return face_uv, valid

    def maps(self, name: str) -> FaceMaps:
        """The look-up tables of face ``name`` (read-only, computed once per camera and face size)."""
        self.face(name)
        return _face_maps(self.camera, self.face_size, name)

    def face_image(self, fisheye_image: np.ndarray, name: str, border_value: int = 0) -> np.ndarray:
        """Face ``name`` of a uint8 fisheye image (grey or colour), bilinear; masked pixels are ``border_value``."""
        self._check_image(fisheye_image)
        self.face(name)
        map_x, map_y = _remap_tables(self.camera, self.face_size, name)
        return cv2.remap(
            fisheye_image, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=border_value
        )

    def cross(self, fisheye_image: np.ndarray) -> np.ndarray:
        """The five faces unfolded as a cross, uint8 (3N, 3N[, channels]); cells without a face are black."""
        self._check_image(fisheye_image)
        n = self.face_size
        canvas = np.zeros((3 * n, 3 * n, *fisheye_image.shape[2:]), dtype=np.uint8)
        for name, (row, column) in CROSS_CELLS.items():
            canvas[row * n : (row + 1) * n, column * n : (column + 1) * n] = self.face_image(fisheye_image, name)
        return canvas

    def _check_image(self, image: np.ndarray) -> None:
        """A ValueError unless ``image`` is a uint8 grey or colour image of the camera's size."""
        image = np.asarray(image)
        if image.ndim not in (2, 3):
            raise ValueError(f"fisheye image must be (height, width) or (height, width, channels), got {image.shape}")
        height, width = image.shape[:2]
        if (width, height) != (self.camera.width, self.camera.height):
            raise ValueError(
                f"fisheye image is {width}x{height} pixels but the camera is calibrated for "
                f"{self.camera.width}x{self.camera.height} (width x height)"
            )
        if image.dtype != np.uint8:
            raise ValueError(f"fisheye image must be uint8, got {image.dtype}")


def _rotate(rotation: Rotation, vectors) -> np.ndarray:
    """``rotation`` applied to vectors of shape (..., 3); a ValueError for any other shape."""
    vectors = np.asarray(vectors, dtype=np.float64)
    if vectors.ndim == 0 or vectors.shape[-1] != 3:
        raise ValueError(f"rays must have shape (..., 3), got shape {vectors.shape}")
    return rotation.apply(vectors.reshape(-1, 3)).reshape(vectors.shape)


@functools.lru_cache(maxsize=32)
def _face_maps(camera: CameraModel, size: int, name: str) -> FaceMaps:
    """Eqs. 13-18 over every pixel centre of a face, as float32 tables; computed once per arguments."""
    cubemap = Cubemap(camera, size)
    fisheye_uv, valid = cubemap.face_to_fisheye(name, cubemap.faces[name].pinhole.pixel_grid())
    tables = FaceMaps(fisheye_uv[..., 0].astype(np.float32), fisheye_uv[..., 1].astype(np.float32), valid)
    for table in tables:
        table.flags.writeable = False
    return tables


@functools.lru_cache(maxsize=32)
def _remap_tables(camera: CameraModel, size: int, name: str) -> tuple[np.ndarray, np.ndarray]:
    """``cv2.remap`` tables of a face: valid pixels clamped onto the image's pixel centres, masked ones far outside.

    A valid fisheye pixel within half a pixel of the image's edge reads the edge pixel (clamping
    there is replicating it); a masked one reads only the border value.
    """
    map_x, map_y, valid = _face_maps(camera, size, name)
    remap_x = np.where(valid, np.clip(map_x, 0.0, camera.width - 1.0), _OUTSIDE).astype(np.float32)
    remap_y = np.where(valid, np.clip(map_y, 0.0, camera.height - 1.0), _OUTSIDE).astype(np.float32)
    return remap_x, remap_y
