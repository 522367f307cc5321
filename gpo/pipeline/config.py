"""A run's config: everything a run needs (``OdometryConfig``), read from and written to one YAML file.

The file's schema, with every key's type, range and unit, is ``gpo.pipeline.schema``; this module turns a checked
file into the stages' parameters and back.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields
from enum import StrEnum
from importlib import resources
from pathlib import Path

import numpy as np
import yaml

from gpo.cameras.rig import Rig
from gpo.cameras.targets import Chessboard, FloorBoard
from gpo.floor_image.image import FLOOR_METRES_PER_PIXEL, FLOOR_X_RANGE_M, FLOOR_Y_RANGE_M, FloorImage
from gpo.fusion import FusionSettings
from gpo.io.outputs import write_text
from gpo.motion.keyframes import KeyframePolicy
from gpo.motion.keypoints import FeatureParameters
from gpo.motion.klt import KLTParameters
from gpo.odometry.estimators import ESTIMATORS, FloorEstimator
from gpo.odometry.kinematics import PaperBicycle
from gpo.pipeline.schema import ConfigFile, FloorImageSection, read_config, rig_from_config, rig_to_dict


class Route(StrEnum):
    """How a camera frame becomes what the motion is measured on (``OdometryConfig`` says what each does)."""

    ANALYTIC = "analytic"
    ORTHO_GPI = "ortho-gpi"
    GPI = "gpi"
    KEYPOINTS = "keypoints"


FUSED = "fused"
"""The method that fuses a floor estimator's odometry with the tracking camera's (``gpo.fusion``)."""
ROUTES = tuple(Route)
VECTORS = ("median", "mean")
DEFAULT_CONFIG = "sim_t265.yaml"


def floor_methods() -> tuple[str, ...]:
    """The floor motion estimators' names (``gpo.odometry.estimators.ESTIMATORS``), in the registry's order."""
    return tuple(ESTIMATORS)


def methods() -> tuple[str, ...]:
    """Every ``odometry.method`` a config may name: the floor estimators and ``fused``."""
    return (*floor_methods(), FUSED)


@dataclass(frozen=True, eq=False)
class OdometryConfig:
    """Everything a run needs: the ``rig``, the ``floor`` image, the KLT ``klt`` parameters, the ``keyframe`` policy
    of the estimators that measure from keyframes (``gpo.motion.keyframes``; the paper's ``gpo`` measures frame to
    frame whatever it says), the paper's bicycle ``model``, the ``method`` (one of ``methods()``: a floor estimator of
    ``gpo.odometry.estimators`` or ``fused``), the ``vector`` statistic (median or mean; for ``gpo`` and
    ``gpo-exact``), ``max_gap_s``, the longest time the robot coasts or a frame gap is bridged, seconds, the
    ``fusion`` settings of the ``fused`` method, and the ``route`` that makes the floor image (``floor_table``):

    - ``analytic``: each floor point projected through the calibrated camera from the rig's mount (no chessboard);
    - ``ortho-gpi``: the first paper's chessboard route, fisheye -> cubemap -> GPI -> ortho-GPI, calibrated on
      ``board_image``, a frame of the chessboard ``board`` lying on the floor where ``board`` says;
    - ``gpi``: the plain GPI of the same frame, its own approximate scale and place taken for true;
    - ``keypoints``: no floor image; the ``features`` method detects keypoints in the camera image and turns each
      into a floor point (``gpo.floor_image.analytic.pixels_to_floor``: undistortion, the mount's tilt, its height),
      the second paper's way.

    ``features``: the keypoint detector, matching and filters of the ``features`` method (``gpo.motion.keypoints``)."""

    rig: Rig
    floor: FloorImage
    klt: KLTParameters = field(default_factory=KLTParameters)
    keyframe: KeyframePolicy = field(default_factory=KeyframePolicy)
    model: PaperBicycle | None = None
    method: str = "gpo-exact"
    vector: str = "median"
    max_gap_s: float = 0.5
    fusion: FusionSettings = field(default_factory=FusionSettings)
    route: Route = Route.ANALYTIC
    board_image: Path | None = None
    board: FloorBoard | None = None
    features: FeatureParameters = field(default_factory=FeatureParameters)

    def __post_init__(self):
        if self.route not in ROUTES:
            raise ValueError(f"unknown route {self.route!r}; the routes are {', '.join(ROUTES)}")
        if self.method not in methods():
            raise ValueError(f"unknown method {self.method!r}; the methods are {', '.join(methods())}")
        object.__setattr__(self, "route", Route(self.route))  # a name from a file or the command line, as a member
        object.__setattr__(self, "method", str(self.method))
        if self.route in (Route.ORTHO_GPI, Route.GPI) and (self.board_image is None or self.board is None):
            raise ValueError(f"the {self.route} route needs board_image (a frame of the floor board) and board")
        if self.fusion.floor_method not in floor_methods():
            floor_method = self.fusion.floor_method
            raise ValueError(f"fusion.floor_method must be one of {', '.join(floor_methods())}, got {floor_method!r}")
        if self.route is Route.KEYPOINTS and self.estimator.MOTION != "keypoints":
            method = self.floor_method
            raise ValueError(f"the keypoints route corrects keypoints: it needs a method that reads them, not {method}")
        if self.vector not in VECTORS:
            raise ValueError(f"unknown vector {self.vector!r}; use {' or '.join(VECTORS)}")
        if not self.max_gap_s > 0:
            raise ValueError(f"max_gap_s must be positive, got {self.max_gap_s!r}")
        if self.model is None:
            centre = float(np.mean(self.floor.extent[:2]))
            object.__setattr__(self, "model", PaperBicycle(centre, centre))

    @property
    def floor_method(self) -> str:
        """The floor estimator's name: the method, or for ``fused`` the one it fuses (``fusion.floor_method``)."""
        return self.fusion.floor_method if self.method == FUSED else self.method

    @property
    def estimator(self) -> type[FloorEstimator]:
        """The floor estimator's class (``gpo.odometry.estimators.ESTIMATORS``)."""
        return ESTIMATORS[self.floor_method]

    def replace(self, **changes) -> OdometryConfig:
        """A copy with ``changes`` (any field, e.g. method="gpo")."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        return OdometryConfig(**{**values, **changes})


def load_config(path=None) -> OdometryConfig:
    """The run config of a config YAML (checked by ``gpo.pipeline.schema.read_config``) with the sections
    ``floor_image``, ``klt``, ``keyframe``, ``kinematics``, ``odometry``, ``fusion`` and ``features``; None loads the
    shipped default for the simulated T265 rig. Errors name the file and the key."""
    if path is None:
        with resources.as_file(resources.files("gpo") / "configs" / DEFAULT_CONFIG) as default:
            return load_config(default)
    path = Path(path)
    return config_from(read_config(path), path)


def config_from(document: ConfigFile, path: Path, where: str | None = None) -> OdometryConfig:
    """The run config of the checked config ``document`` of the file ``path`` (the paths in it are relative to its
    folder); errors name ``where`` it came from (default: ``path``)."""
    where = where or str(path)
    rig = rig_from_config(document, path, where)
    kinematics = document.kinematics
    odometry = document.odometry.model_dump(exclude_none=True)
    try:
        model = None if kinematics is None else PaperBicycle(kinematics.wheelbase_m, kinematics.rear_to_reference_m)
        floor = _floor_image(document.floor_image)
        return OdometryConfig(
            rig, floor, document.klt, document.keyframe, model, **odometry, fusion=document.fusion,
            features=document.features, **_route(document.floor_image, path),
        )
    except ValueError as error:
        raise ValueError(f"{where}: {error}") from None


def config_to_dict(config: OdometryConfig) -> dict:
    """The YAML document of ``config`` (``load_config`` reads it back)."""
    x_min, x_max, y_min, y_max = config.floor.extent
    return {
        **rig_to_dict(config.rig),
        "floor_image": {
            "x_range_m": [round(x_min, 9), round(x_max, 9)],
            "y_range_m": [round(y_min, 9), round(y_max, 9)],
            "metres_per_pixel": round(config.floor.metres_per_pixel, 12),
            **_route_to_dict(config),
        },
        "klt": {f.name: getattr(config.klt, f.name) for f in fields(config.klt)},
        "keyframe": {f.name: getattr(config.keyframe, f.name) for f in fields(config.keyframe)},
        "kinematics": {
            "wheelbase_m": config.model.wheelbase_m,
            "rear_to_reference_m": config.model.rear_to_reference_m,
        },
        "odometry": {"method": str(config.method), "vector": config.vector, "max_gap_s": config.max_gap_s},
        "fusion": config.fusion.to_dict(),
        "features": asdict(config.features),
    }


def save_config(path, config: OdometryConfig) -> Path:
    """Write ``config`` as YAML (through a temporary name); return the path."""
    header = "# gpo run config: the rig (camera, mount, topics), the floor image, KLT, the bicycle model, the method\n"
    return write_text(path, header + yaml.safe_dump(config_to_dict(config), sort_keys=False, default_flow_style=None))


def _floor_image(section: FloorImageSection) -> FloorImage:
    try:
        return FloorImage.top_view(
            section.x_range_m or FLOOR_X_RANGE_M,
            section.y_range_m or FLOOR_Y_RANGE_M,
            section.metres_per_pixel or FLOOR_METRES_PER_PIXEL,
        )
    except ValueError as error:
        raise ValueError(f"floor_image: {error}") from None


def _route(section: FloorImageSection, path: Path) -> dict:
    """The floor image's ``route`` and, for the chessboard routes, ``board_image`` (relative to the config file)
    and ``board`` (where it lay in base_link)."""
    route = {"route": section.route}
    if section.board_image is not None:
        route["board_image"] = path.parent / section.board_image
    if section.board is not None:
        board = section.board
        chessboard = Chessboard(board.squares, board.square_m, board.margin_m)
        route["board"] = FloorBoard(chessboard, board.x_m, board.y_m, math.radians(board.yaw_deg))
    return route


def _route_to_dict(config: OdometryConfig) -> dict:
    if config.route in (Route.ANALYTIC, Route.KEYPOINTS):
        return {} if config.route is Route.ANALYTIC else {"route": str(config.route)}
    board = config.board
    return {
        "route": str(config.route),
        "board_image": str(config.board_image),
        "board": {
            "squares": list(board.board.squares),
            "square_m": board.board.square,
            "margin_m": board.board.margin,
            "x_m": board.x,
            "y_m": board.y,
            "yaw_deg": math.degrees(board.yaw),
        },
    }
