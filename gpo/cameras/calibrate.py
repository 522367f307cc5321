# long: one job, a camera's intrinsics by least squares; a hundred lines of it are the method's notes, the docstring
"""Intrinsic camera calibration from chessboard views: a least-squares fit of any camera model to the board's corners.

The corners come from ``gpo.cameras.chessboard`` (its ``CALIBRATION`` search, in board order); this module fits.
The fits of every model and the result share the board's conventions, the rejected views and the uncertainty that
``CalibrationResult`` reports, and ``python -m gpo calibrate`` is a thin command over them.

Every model of ``gpo.cameras`` is fitted (``MODELS``): the fisheye models EUCM (the T265 of the first
paper), double sphere (ds), Kannala-Brandt (kb4) and Mei's unified model with radtan (omni) by our own
least squares, and the pinhole with radial-tangential distortion by OpenCV's ``calibrateCamera``. All
give the same ``CalibrationResult``.

Frames and units
----------------
The camera optical frame: x right, y down, z forward, metres. The board frame is that of
``gpo.cameras.targets.Chessboard``: origin at the outer corner of the squares, x along a row of inner
corners, y along a column, z out of the printed side, so z faces the camera. Pixels are (u, v),
(0, 0) the centre of the top-left pixel. A pose (rotation, position) maps board points into the
camera frame: ``p_cam = rotation.apply(p_board) + position``. Pattern sizes count inner corners, and corners come
in the board's order, both as ``gpo.cameras.chessboard`` says.

Reprojection errors are residuals, projected minus detected pixels. An RMS here is taken over
both coordinates, so it estimates the noise per coordinate; OpenCV's ``calibrateCamera`` reports
the RMS per corner, sqrt(2) times as large. The summary gives both.

The least-squares problem (EUCM; the other fisheye models alike)
----------------------------------------------------------------
Unknowns: the intrinsics theta = (fx, fy, cx, cy, alpha, beta) and, for each view i = 1..V, the
board's pose as a rotation vector r_i and a position t_i. With X_j the inner corners in the board
frame (``Chessboard.inner_corners``), x_ij their detected pixels and pi_theta the EUCM projection
(``gpo.cameras.eucm.EUCM.project``), the residuals are the reprojection errors, in pixels::

    e_ij = pi_theta(R(r_i) X_j + t_i) - x_ij                          (2 per corner)

and ``scipy.optimize.least_squares`` minimises sum_ij sum_(u,v) rho(e_ij^2), rho the Huber loss
with a scale of 1 px, subject to 0 <= alpha <= 1, beta > 0, fx, fy > 0. Its Jacobian is analytic,
by the chain rule through the board point p_ij = R(r_i) X_j + t_i::

    de/dtheta = d pi/d theta                       (EUCM.project_jacobians)
    de/dr_i   = d pi/d p . d(R(r_i) X_j)/d r_i     (d pi/d p from EUCM.project_jacobians,
                                                    dR/dr from cv2.Rodrigues)
    de/dt_i   = d pi/d p

View i's rows touch only theta and (r_i, t_i), so J = [J_theta | blockdiag(J_1, ..., J_V)] is
sparse: 12 non-zeros per row out of 6 + 6 V columns. It is built sparse and handed to the solver dense: with a few
hundred unknowns at most, the trust region's exact steps (an SVD of J) cost milliseconds and reach the minimum in
a few dozen evaluations on any floating-point path, where iterative (LSMR) steps stop wherever rounding leaves them.

The other fisheye models replace theta by their own parameters (``PARAMETER_NAMES``: ds 6, kb4 8,
omni 9) and pi_theta by their own projection and ``project_jacobians``; their bounds are those of
`gpo.cameras.fit.parameter_bounds`. They start from the EUCM fit: its poses, and the model fitted to
the EUCM over the image by `gpo.cameras.fit.fit_model`.

The start needs no input: alpha = 0.5, beta = 1 (a stereographic lens), cx, cy at the image
centre, f such that the image's shorter side spans 180 degrees; each view's pose by PnP on the
rays of its corners; then f on a coarse grid, keeping the one whose views reproject best. From
there the problem is solved twice: with rho(z) = z (plain least squares) to reach the minimum's
basin, then with the Huber loss from that solution (from a far start the robust loss slows the
solver in the valley where f trades off against the boards' distance). Each fit stops when the cost, the step or
the gradient changes by less than ``STOP_TOLERANCE`` (1e-12, relative): a point every floating-point path reaches,
so that two machines agree to about nine significant digits. ``MAX_EVALUATIONS`` is only a safety net; a fit that
reaches it is flagged as not converged.

Uncertainty: with m residuals (2 per corner) and n = 6 + 6 V unknowns, s^2 = sum e^2 / (m - n) and the covariance of the
intrinsics is the theta block of s^2 (J^T J)^-1 at the solution; the standard deviations are the
square roots of its diagonal. They hold where the errors are independent and Gaussian.

Outliers: a view whose corners do not form a grid (out of order, or not the board) is left out
before the fit. After a fit, a view whose RMS reprojection error exceeds 3 times the median
view's (and 0.5 px) is dropped and the rest refitted, until none is left to drop. Then the
boards' normals must spread over at least 10 degrees, or the focal length is not observable.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import scipy.sparse
from scipy.spatial.transform import Rotation
from tqdm.auto import tqdm

from gpo.cameras import MODELS as MODEL_CLASSES
from gpo.cameras.chessboard import (
    check_pattern_size,
    find_corners,
    forms_grid,
    larger_board,
    pattern_hint,
    pattern_text,
    planar_pose,
)
from gpo.cameras.eucm import EUCM
from gpo.cameras.files import Camera
from gpo.cameras.fit import fit_model, parameter_bounds
from gpo.cameras.pinhole import Pinhole
from gpo.cameras.targets import Chessboard

MODELS = tuple(MODEL_CLASSES)  # eucm, ds, kb4, omni, pinhole
PINHOLE_PARAMETER_NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3")
MIN_VIEWS = 3
MAX_RMS_PX = 1.0  # a fit whose RMS reprojection error exceeds this is not a good calibration
HUBER_SCALE_PX = 1.0
OUTLIER_FACTOR = 3.0  # a view is an outlier when its RMS exceeds this multiple of the median view's ...
OUTLIER_FLOOR_PX = 0.5  # ... and this many pixels
MIN_NORMAL_SPREAD = np.radians(10.0)  # boards whose normals all lie closer than this leave f unobservable
BOUND_TOLERANCE = 1e-3  # alpha or beta this close to a bound sits at it
INVALID_RESIDUAL_PX = 100.0  # residual of a corner that leaves the model's valid region during the fit
STOP_TOLERANCE = 1e-12  # the fit stops when the cost, the step or the gradient changes by less (relative)
MAX_EVALUATIONS = 200  # a safety net (see the module docstring)
UNPROJECTABLE = "the fitted model cannot project its corners"
NOT_A_GRID = "its corners do not form the board's grid (out of order or mis-detected)"


class CalibrationError(ValueError):
    """The images or corners cannot give a calibration; the message says why and what to do."""


@dataclass(frozen=True, eq=False)
class CalibrationResult:
    """What a calibration found, and how far to trust it.

    Per-view entries are keyed by the view's index in the input; ``view_names`` names every view
    (a file path or ``view 3``). ``residuals[i]`` (N, 2) are projected minus detected pixels of
    view i's corners; ``board_poses[i]`` = (rotation camera <- board, board origin in the camera
    frame, metres). ``used`` lists the views of the final fit; ``dropped`` says for every other
    view why it was left out. ``warnings`` list what makes the fit not a good calibration; ``ok``
    is true when there is none.
    """

    model: str
    camera: Camera
    std: dict[str, float]
    rms_px: float
    view_rms_px: dict[int, float]
    residuals: dict[int, np.ndarray]
    board_poses: dict[int, tuple[Rotation, np.ndarray]]
    corners: dict[int, np.ndarray]
    view_names: list[str]
    used: list[int]
    dropped: dict[int, str]
    converged: bool
    warnings: list[str]

    @property
    def ok(self) -> bool:
        return not self.warnings

    @property
    def params(self) -> dict[str, float]:
        """The fitted parameters by name, in the order of ``std``."""
        camera = self.camera
        if not isinstance(camera, Pinhole):
            return dict(zip(camera.PARAMETER_NAMES, camera.params.tolist(), strict=True))
        values = (camera.fx, camera.fy, camera.cx, camera.cy, *camera.dist, 0.0)[: len(PINHOLE_PARAMETER_NAMES)]
        return dict(zip(PINHOLE_PARAMETER_NAMES, values, strict=True))

    def summary(self) -> str:
        """The parameters with their standard deviations, the errors, the views left out and the warnings."""
        verdict = "good" if self.ok else "NOT A GOOD CALIBRATION"
        lines = [
            f"{self.model} calibration from {len(self.used)} of {len(self.view_names)} views, "
            f"{self.camera.width} x {self.camera.height} px ({verdict})",
            f"  RMS reprojection error {self.rms_px:.3f} px per coordinate "
            f"({np.sqrt(2.0) * self.rms_px:.3f} px per corner, OpenCV's measure)",
        ]
        for name, value in self.params.items():
            lines.append(f"  {name:<6} = {value:12.6g} +/- {self.std[name]:.2g}")
        rms = np.array(list(self.view_rms_px.values()))
        lines.append(f"  per-view RMS: median {np.median(rms):.3f} px, worst {rms.max():.3f} px")
        lines += [f"  left out: {self.view_names[i]}: {why}" for i, why in sorted(self.dropped.items())]
        lines += [f"  WARNING: {warning}" for warning in self.warnings]
        return "\n".join(lines)


@dataclass(frozen=True, eq=False)
class _Fit:
    """One fit of a model to the views ``used``: poses as rotation vectors and positions (V, 3)."""

    camera: Camera
    std: dict[str, float]
    rotvecs: np.ndarray
    positions: np.ndarray
    converged: bool
    message: str

    def subset(self, keep: list[int]) -> _Fit:
        return _Fit(self.camera, self.std, self.rotvecs[keep], self.positions[keep], self.converged, self.message)


def calibrate_images(
    paths: Sequence,
    pattern_size: tuple[int, int],
    square_m: float,
    model: str = "eucm",
    progress: bool = True,
    fix_k3: bool = False,
) -> CalibrationResult:
    """Calibrate ``model`` from image files of a chessboard of ``pattern_size`` inner corners
    (per row, per column) and squares of ``square_m`` metres; the images are read as grey."""
    per_row, per_column = check_pattern_size(pattern_size)
    if not square_m > 0:
        raise ValueError(f"the square size must be > 0 metres, got {square_m}")
    images = []
    for path in paths:
        if not Path(path).is_file():
            raise FileNotFoundError(f"{path}: no such image file")
        image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        if image is None:
            raise ValueError(f"{path}: not an image that OpenCV can read")
        images.append(image)
    board = Chessboard((per_row + 1, per_column + 1), square_m)
    names = [str(path) for path in paths]
    return calibrate_views(images, board, model, names=names, progress=progress, fix_k3=fix_k3)


def calibrate_views(
    images: Sequence[np.ndarray],
    board: Chessboard,
    model: str = "eucm",
    names: Sequence[str] | None = None,
    progress: bool = False,
    fix_k3: bool = False,
) -> CalibrationResult:
    """Detect ``board`` in grey uint8 ``images`` (all of one size) and calibrate ``model`` from it.

    Images without the board are left out, with the reason, in the result's ``dropped``.
    """
    _check_model(model)
    if not images:
        raise CalibrationError("no images given")
    names = list(names) if names is not None else [f"view {index}" for index in range(len(images))]
    height, width = images[0].shape[:2]
    guess = initial_eucm(width, height) if model != "pinhole" else None
    pattern = pattern_text(board.pattern_size)
    observed, dropped = {}, {}
    for index, image in enumerate(tqdm(images, desc="finding corners", disable=not progress)):
        if image.shape[:2] != (height, width):
            raise CalibrationError(
                f"{names[index]}: image of {image.shape[1]} x {image.shape[0]} px, but {names[0]} has "
                f"{width} x {height} px; calibrate images of one camera at one resolution"
            )
        corners = find_corners(image, board.pattern_size, guess)
        if corners is None:
            dropped[index] = f"no chessboard of {pattern} inner corners found"
        else:
            if not observed:  # the first view with the pattern: is it the whole board?
                _check_whole_board(image, names[index], board)
            observed[index] = corners
    if not observed:
        raise CalibrationError(
            f"no chessboard of {pattern} inner corners (per row x per column) found in any of the "
            f"{len(images)} images. Is the pattern size right? It counts inner corners, where four squares "
            f"meet: a board of 8 x 6 squares has 7 x 5 inner corners."
            f"{pattern_hint(list(images), board.pattern_size, names)}"
        )
    return _calibrate(observed, dropped, names, board, (width, height), model, fix_k3)


def _check_whole_board(image: np.ndarray, name: str, board: Chessboard) -> None:
    """Raise ``CalibrationError`` when the board in ``image`` (named ``name``, one where the pattern was found) has
    more inner corners than ``board``: the corners found are then a part of it, a different part in each view, and
    the fit of such parts is wrong, its focal length several times off."""
    larger = larger_board(image, board.pattern_size)
    if larger is not None:
        (size, whole), given = larger, pattern_text(board.pattern_size)
        found, hint = (pattern_text(size), pattern_text(size)) if whole else (f"at least {pattern_text(size)}", "as")
        raise CalibrationError(
            f"{name} shows a board of {found} inner corners, more than the {given} given: give --board {hint} (the "
            "whole board's inner corners per row x per column; a part of a board gives a wrong calibration)"
        )


def calibrate_corners(
    corners: Sequence[np.ndarray | None],
    board: Chessboard,
    image_size: tuple[int, int],
    model: str = "eucm",
    names: Sequence[str] | None = None,
    fix_k3: bool = False,
    max_iterations: int = MAX_EVALUATIONS,
    zero: Sequence[str] = (),
    prior: CalibrationResult | None = None,
) -> CalibrationResult:
    """Calibrate ``model`` from corners already found: one (N, 2) pixel array per view, in the order
    of ``board.inner_corners()``, or None for a view without the board. ``image_size`` = (width, height).

    For the fisheye models, ``zero`` names parameters held at 0 (e.g. ``("p1", "p2")``: an omni without
    tangential distortion) and ``prior``, a calibration of the same views by any model, is the start
    (which saves the EUCM fit the other models otherwise start from)."""
    _check_model(model)
    names = list(names) if names is not None else [f"view {index}" for index in range(len(corners))]
    count = len(board.inner_corners())
    observed, dropped = {}, {}
    for index, view in enumerate(corners):
        if view is None:
            dropped[index] = "no corners"
            continue
        view = np.asarray(view, dtype=np.float64)
        if view.shape != (count, 2):
            raise CalibrationError(f"{names[index]}: corners of shape {view.shape}, expected ({count}, 2)")
        observed[index] = view
    return _calibrate(observed, dropped, names, board, image_size, model, fix_k3, max_iterations, tuple(zero), prior)


def _calibrate(
    observed, dropped, names, board, image_size, model, fix_k3=False, max_iterations=MAX_EVALUATIONS, zero=(),
    prior=None,
):
    scrambled = {index for index, corners in observed.items() if not forms_grid(corners, board.pattern_size)}
    dropped = {**dropped, **dict.fromkeys(scrambled, NOT_A_GRID)}
    observed = {index: corners for index, corners in observed.items() if index not in scrambled}
    if len(observed) < MIN_VIEWS:
        reasons = "".join(f"\n  {names[index]}: {why}" for index, why in sorted(dropped.items()))
        raise CalibrationError(
            f"only {len(observed)} usable view(s) of the board, but a calibration needs at least {MIN_VIEWS} "
            f"(better 15 or more, the board tilted and spread over the whole image){reasons}"
        )
    width, height = image_size
    if model == "pinhole":
        fit = _pinhole_fitter(observed, board, width, height, fix_k3, max_iterations)
    else:
        fit = _model_fitter(model, observed, board, width, height, max_iterations, zero, prior)
    fitted, used, outliers = _fit_rejecting_outliers(fit, observed, board)
    _check_tilts(fitted)
    return _result(model, fitted, used, observed, {**dropped, **outliers}, names, board)


def _check_model(model: str) -> None:
    if model not in MODELS:
        raise ValueError(f"unknown camera model '{model}'; choose one of {', '.join(MODELS)}")


def initial_eucm(width: int, height: int, focal: float | None = None) -> EUCM:
    """A starting EUCM that needs no input: alpha = 0.5 and beta = 1 (stereographic), the
    principal point at the image centre and f such that the shorter side spans 180 degrees."""
    focal = min(width, height) / 4.0 if focal is None else focal
    return EUCM(focal, focal, (width - 1) / 2.0, (height - 1) / 2.0, 0.5, 1.0, width, height)


def board_pose(camera: Camera, board: Chessboard, corners: np.ndarray):
    """Board pose (rotation camera <- board, position in metres) from its corners' pixels (N, 2), or None: the
    corners unprojected to rays, posed by ``gpo.cameras.chessboard.planar_pose``."""
    rays, valid = camera.unproject(corners)
    if valid.sum() < 4:
        return None
    return planar_pose(rays[valid], board.inner_corners()[valid])


def _view_rms(camera, board: Chessboard, pose, corners: np.ndarray) -> float:
    """RMS reprojection error of one view per coordinate, pixels; inf where a corner does not project."""
    rotation, position = pose
    pixels, valid = camera.project(rotation.apply(board.inner_corners()) + position)
    return _rms(pixels - corners) if valid.all() else np.inf


def _rms(errors: np.ndarray) -> float:
    """Root mean square of the residuals over both coordinates, pixels (NaN, where a corner does not
    project, left out); OpenCV's RMS per corner is sqrt(2) times this."""
    return float(np.sqrt(np.nanmean(errors**2)))


def _initial_eucm_fit(observed: dict[int, np.ndarray], board: Chessboard, width: int, height: int) -> _Fit:
    """The start of the least squares: f on a grid from half to 4 times the default, keeping the one
    whose views, posed by ``board_pose``, reproject with the lowest median RMS."""
    views = list(observed.values())
    best = None
    for scale in 2.0 ** (np.arange(-4, 9) / 4.0):
        camera = initial_eucm(width, height, scale * min(width, height) / 4.0)
        poses = [board_pose(camera, board, corners) for corners in views]
        if any(pose is None for pose in poses):
            continue
        score = np.median([_view_rms(camera, board, pose, c) for pose, c in zip(poses, views, strict=True)])
        if best is None or score < best[0]:
            best = score, camera, poses
    if best is None:
        raise CalibrationError("no starting focal length poses every view; are the corners right?")
    _, camera, poses = best
    rotvecs = np.array([rotation.as_rotvec() for rotation, _ in poses])
    positions = np.array([position for _, position in poses])
    return _Fit(camera, {}, rotvecs, positions, True, "start")


class _ModelProblem:
    """Residuals and sparse Jacobian of the least squares over x = (theta, r_1, t_1, ..., r_V, t_V) for the
    camera model class ``model`` with n = len(model.PARAMETER_NAMES) intrinsics theta."""

    def __init__(self, model: type, board: Chessboard, observed: np.ndarray, width: int, height: int, zero=()):
        self.model = model
        self.points = board.inner_corners()  # X_j, (N, 3)
        self.observed = observed  # x_ij, (V, N, 2)
        self.width, self.height = width, height
        # the intrinsics solved for; those named in ``zero`` are held at 0
        self.free = np.array([i for i, name in enumerate(model.PARAMETER_NAMES) if name not in zero])
        n = self.intrinsics = len(self.free)
        views, count = observed.shape[:2]
        rows = views * count * 2
        # each row: the n intrinsics, then its view's six pose columns
        pose_columns = n + 6 * np.arange(views)[:, None] + np.arange(6)
        columns = np.concatenate([np.broadcast_to(np.arange(n), (views, n)), pose_columns], axis=1)
        self.indices = np.broadcast_to(columns[:, None, None, :], (views, count, 2, n + 6)).ravel()
        self.indptr = np.arange(0, (n + 6) * rows + 1, n + 6)
        self.shape = (rows, n + 6 * views)

    def pack(self, fit: _Fit) -> np.ndarray:
        return np.concatenate([fit.camera.params[self.free], np.column_stack([fit.rotvecs, fit.positions]).ravel()])

    def unpack(self, x: np.ndarray):
        params = np.zeros(len(self.model.PARAMETER_NAMES))
        params[self.free] = x[: self.intrinsics]
        camera = self.model.from_params(params, self.width, self.height)
        poses = x[self.intrinsics :].reshape(-1, 6)
        return camera, poses[:, :3], poses[:, 3:]

    def _points_in_camera(self, rotvecs, positions):
        """Corners in the camera frame (V, N, 3) and d(R X)/d r (V, N, 3, 3), from ``cv2.Rodrigues``."""
        rotations, derivatives = [], []
        for rotvec in rotvecs:
            rotation, jacobian = cv2.Rodrigues(rotvec)
            rotations.append(rotation)
            derivatives.append(jacobian.reshape(3, 3, 3))  # [k, i, j] = d R_ij / d r_k
        rotations, derivatives = np.array(rotations), np.array(derivatives)
        points = np.einsum("vij,nj->vni", rotations, self.points) + positions[:, None, :]
        d_points_d_rotvec = np.einsum("vkij,nj->vnik", derivatives, self.points)
        return points, d_points_d_rotvec

    def residuals(self, x: np.ndarray) -> np.ndarray:
        camera, rotvecs, positions = self.unpack(x)
        points, _ = self._points_in_camera(rotvecs, positions)
        pixels, valid = camera.project(points)
        errors = pixels - self.observed
        errors[~valid] = INVALID_RESIDUAL_PX
        return errors.ravel()

    def dense_jacobian(self, x: np.ndarray) -> np.ndarray:
        """``jacobian`` as a dense array, for the trust region's exact (SVD) steps."""
        return self.jacobian(x).toarray()

    def jacobian(self, x: np.ndarray) -> scipy.sparse.csr_matrix:
        camera, rotvecs, positions = self.unpack(x)
        points, d_points_d_rotvec = self._points_in_camera(rotvecs, positions)
        d_pixels_d_point, d_pixels_d_theta = camera.project_jacobians(points)  # (V, N, 2, 3), (V, N, 2, n)
        d_pixels_d_rotvec = d_pixels_d_point @ d_points_d_rotvec
        blocks = np.concatenate([d_pixels_d_theta[..., self.free], d_pixels_d_rotvec, d_pixels_d_point], axis=-1)
        blocks = np.nan_to_num(blocks, nan=0.0)  # a corner outside the valid region: constant residual
        return scipy.sparse.csr_matrix((blocks.ravel(), self.indices, self.indptr), shape=self.shape)


def _model_fitter(
    model, observed, board, width, height, max_iterations, zero=(), prior: CalibrationResult | None = None
) -> Callable[[list[int], _Fit | None], _Fit]:
    """A function fitting the fisheye ``model`` to the views ``used``, from a given start. Without one it
    starts from ``prior`` (a calibration of any model whose views include ``used``: its camera fitted to
    ``model``, its poses), else the EUCM from ``_initial_eucm_fit``, and any other model from the EUCM
    fitted first (see the module docstring). Parameters named in ``zero`` are held at 0."""
    cls = MODEL_CLASSES[model]
    unknown = sorted(set(zero) - set(cls.PARAMETER_NAMES))
    if unknown:
        raise ValueError(f"{model} has no parameter {', '.join(unknown)}; its are {', '.join(cls.PARAMETER_NAMES)}")

    def fit(used: list[int], start: _Fit | None) -> _Fit:
        from scipy.optimize import least_squares  # imported by what calibrates, not by every command

        views = {index: observed[index] for index in used}
        if start is None and prior is not None and set(used) <= set(prior.board_poses):
            camera = prior.camera if prior.model == model else fit_model(prior.camera, model).camera
            poses = [prior.board_poses[index] for index in used]
            rotvecs = np.array([rotation.as_rotvec() for rotation, _ in poses])
            start = _Fit(camera, {}, rotvecs, np.array([position for _, position in poses]), True, "prior")
        elif start is None and model == "eucm":
            start = _initial_eucm_fit(views, board, width, height)
        elif start is None:
            eucm = _model_fitter("eucm", observed, board, width, height, max_iterations)(used, None)
            camera = fit_model(eucm.camera, model).camera
            start = _Fit(camera, {}, eucm.rotvecs, eucm.positions, True, "start")
        problem = _ModelProblem(cls, board, np.array(list(views.values())), width, height, zero)
        lower = np.full(problem.shape[1], -np.inf)
        upper = np.full(problem.shape[1], np.inf)
        low, high = parameter_bounds(model)
        lower[: problem.intrinsics], upper[: problem.intrinsics] = low[problem.free], high[problem.free]
        solve = functools.partial(
            least_squares,
            problem.residuals,
            jac=problem.dense_jacobian,
            bounds=(lower, upper),
            x_scale="jac",
            tr_solver="exact",
            ftol=STOP_TOLERANCE,
            xtol=STOP_TOLERANCE,
            gtol=STOP_TOLERANCE,
            max_nfev=max_iterations,
        )
        plain = solve(problem.pack(start), loss="linear")
        solution = solve(plain.x, loss="huber", f_scale=HUBER_SCALE_PX)
        camera, rotvecs, positions = problem.unpack(solution.x)
        std = np.zeros(len(cls.PARAMETER_NAMES))  # a parameter held at zero: exactly zero
        std[problem.free] = _intrinsics_std(problem.jacobian(solution.x), solution.fun, problem.intrinsics)
        return _Fit(
            camera,
            dict(zip(cls.PARAMETER_NAMES, std.tolist(), strict=True)),
            rotvecs,
            positions,
            plain.status > 0 and solution.status > 0,
            solution.message if plain.status > 0 else plain.message,
        )

    return fit


def _intrinsics_std(jacobian: scipy.sparse.csr_matrix, residuals: np.ndarray, count: int) -> np.ndarray:
    """Standard deviations of the ``count`` intrinsics: the theta block of s^2 (J^T J)^-1, s^2 = sum e^2 / (m - n)."""
    rows, unknowns = jacobian.shape
    variance = residuals @ residuals / max(rows - unknowns, 1)
    normal = (jacobian.T @ jacobian).toarray()
    scale = np.sqrt(np.diag(normal))  # inverted with unit diagonal: intrinsics and poses differ by orders of magnitude
    scale[scale == 0] = 1.0
    try:
        scales = np.outer(scale, scale)
        covariance = variance * (np.linalg.inv(normal / scales) / scales)[:count, :count]
    except np.linalg.LinAlgError:
        return np.full(count, np.inf)
    return np.sqrt(np.abs(np.diag(covariance)))


def _pinhole_fitter(observed, board, width, height, fix_k3, max_iterations):
    """A function fitting the pinhole with (k1, k2, p1, p2, k3) to the views ``used``, by OpenCV
    (which ignores ``start``: it begins from its own closed-form estimate from the homographies)."""
    points = board.inner_corners().astype(np.float32)

    def fit(used: list[int], start: _Fit | None) -> _Fit:
        image_points = [observed[index].astype(np.float32) for index in used]
        criteria = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, max_iterations, 1e-12)
        try:
            _, matrix, dist, rotvecs, positions, std, _, _ = cv2.calibrateCameraExtended(
                [points] * len(used),
                image_points,
                (width, height),
                None,
                None,
                flags=cv2.CALIB_FIX_K3 if fix_k3 else 0,
                criteria=criteria,
            )
        except cv2.error as error:
            raise CalibrationError(f"OpenCV could not fit the pinhole model: {error.err}") from None
        fx, fy, cx, cy = (float(matrix[row, column]) for row, column in ((0, 0), (1, 1), (0, 2), (1, 2)))
        camera = Pinhole(fx, fy, cx, cy, dist.ravel()[:5], width, height)
        return _Fit(
            camera,
            dict(zip(PINHOLE_PARAMETER_NAMES, std.ravel()[:9].tolist(), strict=True)),
            np.array(rotvecs).reshape(-1, 3),
            np.array(positions).reshape(-1, 3),
            True,
            "calibrateCamera",
        )

    return fit


def _poses(fitted: _Fit) -> list[tuple[Rotation, np.ndarray]]:
    return [(Rotation.from_rotvec(r), p) for r, p in zip(fitted.rotvecs, fitted.positions, strict=True)]


def _fit_rejecting_outliers(fit, observed: dict[int, np.ndarray], board: Chessboard):
    """Fit, drop the views whose RMS exceeds ``OUTLIER_FACTOR`` x the median view's (and
    ``OUTLIER_FLOOR_PX``), refit from the last solution; until no view is dropped."""
    used = sorted(observed)
    fitted = fit(used, None)
    dropped = {}
    while True:
        rms = [_view_rms(fitted.camera, board, pose, observed[i]) for pose, i in zip(_poses(fitted), used, strict=True)]
        threshold = max(OUTLIER_FACTOR * float(np.median(rms)), OUTLIER_FLOOR_PX)
        keep = [k for k, value in enumerate(rms) if value <= threshold]
        if len(keep) == len(used) or len(keep) < MIN_VIEWS:
            return fitted, used, dropped
        for k in set(range(len(used))) - set(keep):
            dropped[used[k]] = (
                f"outlier: RMS reprojection error {rms[k]:.2f} px > {threshold:.2f} px "
                f"({OUTLIER_FACTOR:g} x the median view's)"
                if np.isfinite(rms[k])
                else UNPROJECTABLE
            )
        used = [used[k] for k in keep]
        fitted = fit(used, fitted.subset(keep))


def _check_tilts(fitted: _Fit) -> None:
    """Raise when the boards' normals are (nearly) parallel: then f trades off against distance."""
    normals = Rotation.from_rotvec(fitted.rotvecs).apply([0.0, 0.0, 1.0])
    spread = np.arccos(np.clip(np.min(normals @ normals.T), -1.0, 1.0))
    if spread < MIN_NORMAL_SPREAD:
        raise CalibrationError(
            f"the board's orientation hardly changes between views (its normals lie within "
            f"{np.degrees(spread):.1f} degrees of one another), so the focal length cannot be told from the "
            f"distance: tilt the board, by 20 to 45 degrees in different directions, in many of the views"
        )


def _result(model, fitted: _Fit, used, observed, dropped, names, board: Chessboard) -> CalibrationResult:
    camera = fitted.camera
    poses = dict(zip(used, _poses(fitted), strict=True))
    residuals, invalid = {}, 0
    for index, (rotation, position) in poses.items():
        pixels, valid = camera.project(rotation.apply(board.inner_corners()) + position)
        residuals[index] = pixels - observed[index]
        invalid += int((~valid).sum())
    view_rms = {index: _rms(errors) for index, errors in residuals.items()}
    rms = _rms(np.concatenate(list(residuals.values())))
    warnings = []
    unprojectable = [names[index] for index, why in dropped.items() if why == UNPROJECTABLE]
    if unprojectable:
        warnings.append(
            f"the fitted model cannot project the corners of {', '.join(unprojectable)} (they lie beyond "
            "its valid region): the lens is wider than this model can hold"
        )
    if not fitted.converged:
        warnings.append(f"the fit did not converge ({fitted.message}); more views, or check the corners")
    if invalid:
        warnings.append(f"{invalid} corners fall outside the fitted model's valid region")
    if not rms <= MAX_RMS_PX:
        hint = "is the lens a fisheye (model 'eucm')" if model == "pinhole" else "are the images blurred"
        warnings.append(
            f"RMS reprojection error {rms:.2f} px > {MAX_RMS_PX:g} px: the {model} model does not explain the "
            f"corners; {hint}, or are corners mis-detected?"
        )
    if not isinstance(camera, Pinhole):
        warnings += _bound_warnings(model, camera)
    if not all(np.isfinite(list(fitted.std.values()))):
        warnings.append("some parameters are not determined by these views (infinite standard deviation)")
    return CalibrationResult(
        model,
        camera,
        fitted.std,
        rms,
        view_rms,
        residuals,
        poses,
        {index: observed[index] for index in used},
        list(names),
        list(used),
        dict(sorted(dropped.items())),
        fitted.converged,
        warnings,
    )


def _bound_warnings(model: str, camera) -> list[str]:
    """A warning for each shape parameter (not fx, fy) that sits at a bound of `parameter_bounds`."""
    warnings = []
    for name, value, low, high in zip(camera.PARAMETER_NAMES, camera.params, *parameter_bounds(model), strict=True):
        if name in ("fx", "fy") or not (value - low < BOUND_TOLERANCE or high - value < BOUND_TOLERANCE):
            continue
        hint = "; alpha = 0 is a pinhole: if the lens is not a fisheye, use model 'pinhole'" if name == "alpha" else ""
        warnings.append(
            f"{name} = {value:.4g} sits at its bound ({low:g} <= {name} <= {high:g}), where the standard "
            f"deviations do not hold{hint}"
        )
    return warnings
