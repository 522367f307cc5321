"""One YAML file describes a rig and a run, checked by one schema (``ConfigFile``).

::

    name: t265
    camera:                        # a Kalibr camchain entry, written inline ...
      camera_model: eucm
      intrinsics: [0.6, 1.1, 286.0, 286.0, 424.0, 400.0]
      distortion_model: none
      distortion_coeffs: []
      resolution: [848, 800]
    # camchain: calib/camchain.yaml  ... or a Kalibr camchain file (relative to this file)
    # camchain_camera: cam0          ... and the camera's name in it (default: the first)
    mount:                         # the camera's body frame (x forward, y left, z up) in base_link
      position_m: [0.6, 0.0, 0.12]
      rpy_deg: [1.5, 6.0, 0.0]     # roll, pitch (positive looks down), yaw; REP-103 fixed axes x, y, z
      # quaternion_xyzw: [...]     # or the optical frame's orientation (x right, y down, z forward) in base_link;
                                   # given with rpy_deg, both must describe the same orientation
    rate_hz: 30.0
    frame_id: camera_fisheye1_optical_frame
    topics:
      image: /camera/fisheye1/image_raw
      camera_info: /camera/fisheye1/camera_info

and the run's sections: ``floor_image``, ``klt``, ``keyframe``, ``kinematics``, ``odometry``, ``fusion``,
``features`` (``gpo.pipeline.config.load_config``). Every section and key is checked before anything runs: types,
ranges, finite numbers, and unknown keys at every level (with the nearest known one). The ``klt``, ``keyframe``,
``fusion`` and ``features`` sections are the fields of ``KLTParameters``, ``KeyframePolicy``, ``FusionSettings`` and
``FeatureParameters`` themselves, so a field added there is a key of the file at once; a key of the other sections
is one line of its section below. Errors name the file, the key and what is allowed; YAML errors name the line. A
document whose aliases would expand beyond ``MAX_NODES`` nodes (a "billion laughs") is refused before it is built.
"""

from __future__ import annotations

import difflib
import re
import typing
from dataclasses import fields, is_dataclass
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator
from scipy.spatial.transform import Rotation

from gpo.cameras.files import Camera, camera_from_kalibr, camera_to_kalibr, load_basalt, load_kalibr
from gpo.cameras.rig import CameraMount, Rig
from gpo.fusion import FusionSettings
from gpo.io.outputs import write_text
from gpo.motion.keyframes import KeyframePolicy
from gpo.motion.keypoints import FeatureParameters
from gpo.motion.klt import KLTParameters

MAX_BYTES = 1_000_000
"""The largest config file read, bytes."""
MAX_NODES = 100_000
"""The most YAML nodes a config may hold once its aliases are expanded."""

Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]
Name = Annotated[str, Field(min_length=1)]
Vector3 = tuple[float, float, float]


class Section(BaseModel):
    """A mapping of the file: its keys are its fields, nothing else; numbers finite."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class CameraSection(Section):
    """A Kalibr camchain entry (``gpo.cameras.files``); Kalibr's extrinsic keys are allowed and not read."""

    camera_model: Name
    intrinsics: list[float]
    distortion_model: str = "none"
    distortion_coeffs: list[float] | None = None
    resolution: tuple[Annotated[int, Field(ge=1)], Annotated[int, Field(ge=1)]]
    rostopic: str | None = None
    cam_overlaps: list[int] | None = None
    T_cam_imu: list[list[float]] | None = None
    T_cn_cnm1: list[list[float]] | None = None
    timeshift_cam_imu: float | None = None


class MountSection(Section):
    """The camera in base_link: ``position_m`` (metres) with ``rpy_deg`` (roll, pitch, yaw of the camera's body
    frame, degrees) or ``quaternion_xyzw`` (its optical frame), or both if they agree (``_mount``); ``height_m``,
    ``pitch_deg`` and ``roll_deg`` are for people and only checked."""

    position_m: Vector3
    quaternion_xyzw: tuple[float, float, float, float] | None = None
    rpy_deg: Vector3 | None = None
    height_m: float | None = None
    pitch_deg: float | None = None
    roll_deg: float | None = None

    @field_validator("quaternion_xyzw")
    @classmethod
    def _unit_length_possible(cls, value):
        if value is not None and np.linalg.norm(value) < 1e-9:
            raise ValueError("a rotation's quaternion cannot be all zeros")
        return value

    @model_validator(mode="after")
    def _an_orientation(self):
        if self.rpy_deg is None and self.quaternion_xyzw is None:
            raise ValueError(
                "no orientation: give rpy_deg: [roll, pitch, yaw] in degrees (the camera's body frame, x forward, "
                "y left, z up, in base_link) or quaternion_xyzw (its optical frame)"
            )
        return self


class TopicsSection(Section):
    image: Name
    camera_info: str = ""


class BoardSection(Section):
    """A chessboard lying on the floor: ``squares`` (per row, per column), square and margin sizes (metres), and
    where it lay in base_link (``x_m``, ``y_m``, ``yaw_deg``)."""

    squares: tuple[Annotated[int, Field(ge=2)], Annotated[int, Field(ge=2)]]
    square_m: Positive
    margin_m: NonNegative
    x_m: float
    y_m: float
    yaw_deg: float


class FloorImageSection(Section):
    """The floor image: extent (metres, base_link), pixel size, and the route that makes it (``gpo.pipeline``);
    unset keys take the pipeline's defaults."""

    x_range_m: tuple[float, float] | None = None
    y_range_m: tuple[float, float] | None = None
    metres_per_pixel: Positive | None = None
    route: str = "analytic"
    board_image: str | None = None
    board: BoardSection | None = None


class KinematicsSection(Section):
    wheelbase_m: Positive
    rear_to_reference_m: NonNegative


class OdometrySection(Section):
    method: str | None = None
    vector: str | None = None
    max_gap_s: Positive | None = None


class ConfigFile(Section):
    """The whole file: the rig (``name``, ``camera`` or ``camchain``, ``mount``, ``rate_hz``, ``frame_id``,
    ``topics``) and the run's sections."""

    name: Name
    camera: CameraSection | None = None
    camchain: str | None = None
    camchain_camera: str | None = None
    mount: MountSection
    rate_hz: Positive
    frame_id: Name
    topics: TopicsSection
    floor_image: FloorImageSection = FloorImageSection()
    klt: KLTParameters = KLTParameters()
    keyframe: KeyframePolicy = KeyframePolicy()
    kinematics: KinematicsSection | None = None
    odometry: OdometrySection = OdometrySection()
    fusion: FusionSettings = FusionSettings()
    features: FeatureParameters = FeatureParameters()

    @model_validator(mode="after")
    def _one_camera(self):
        if (self.camera is None) == (self.camchain is None):
            raise ValueError("give either 'camera' (a Kalibr camchain entry) or 'camchain' (a camchain file), one")
        return self


def read_yaml(path) -> Any:
    """The YAML document of the file ``path``; errors name the file (and the line, for YAML errors)."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{path} is a folder; expected a YAML file")
    if not path.is_file():
        raise FileNotFoundError(f"no file {path}: expected a YAML file")
    if path.stat().st_size > MAX_BYTES:
        raise ValueError(f"{path} is {path.stat().st_size} bytes; a config is at most {MAX_BYTES}")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{path} is not a text file (UTF-8); expected YAML") from None
    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        if node is not None and _expanded_nodes(node, {}) > MAX_NODES:
            raise ValueError(f"{path}: its aliases expand to more than {MAX_NODES} YAML nodes; refused")
        return None if node is None else loader.construct_document(node)
    except yaml.MarkedYAMLError as error:
        mark = error.problem_mark or error.context_mark
        where = f", line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ValueError(f"{path}{where}: not valid YAML: {error.problem or error.context}") from None
    except yaml.YAMLError as error:
        raise ValueError(f"{path}: not valid YAML: {error}") from None
    finally:
        loader.dispose()


def _expanded_nodes(node: yaml.Node, counted: dict[int, int]) -> int:
    """How many nodes ``node`` becomes with every alias expanded (each shared node counted once per use)."""
    if id(node) in counted:
        return counted[id(node)]
    counted[id(node)] = 1  # a node that refers to itself counts once
    if isinstance(node, yaml.SequenceNode):
        total = 1 + sum(_expanded_nodes(child, counted) for child in node.value)
    elif isinstance(node, yaml.MappingNode):
        total = 1 + sum(_expanded_nodes(k, counted) + _expanded_nodes(v, counted) for k, v in node.value)
    else:
        total = 1
    counted[id(node)] = total
    return total


def read_config(path) -> ConfigFile:
    """The checked config file ``path`` (``ConfigFile``); a ValueError lists every problem, each with the key."""
    path = Path(path)
    document = read_yaml(path)
    if not isinstance(document, dict):
        raise ValueError(
            f"{path}: a config is a YAML mapping of {', '.join(ConfigFile.model_fields)}; got {type(document).__name__}"
        )
    try:
        return ConfigFile.model_validate(document)
    except ValidationError as error:
        raise ValueError(f"{path}: " + "\n  ".join(_problem(e) for e in error.errors()[:8])) from None


def _problem(error: dict) -> str:
    """One schema error as people read it: the key's path, what is wrong, what is allowed."""
    location = [part for part in error["loc"] if not isinstance(part, int)]
    where = ".".join(str(part) for part in error["loc"]) or "the file"
    if error["type"] in ("extra_forbidden", "unexpected_keyword_argument"):
        known = _keys(location[:-1])
        close = difflib.get_close_matches(str(location[-1]), known, n=1)
        hint = f"did you mean {close[0]}? " if close else ""
        section = ".".join(map(str, location[:-1])) or "the file"
        return f"{where}: unknown key; {hint}the keys of {section} are {', '.join(known)}"
    message = re.sub(r" or (an )?instance of \w+", "", error["msg"].removeprefix("Value error, "))
    if error["type"] == "missing":
        return f"{where}: missing; it is required"
    shown = repr(error["input"])
    return f"{where}: {message} (got {shown if len(shown) < 60 else shown[:57] + '...'})"


def _keys(location: list) -> list[str]:
    """The keys allowed at ``location`` (a list of keys from the top of the file)."""
    kind: Any = ConfigFile
    for key in location:
        hints = typing.get_type_hints(kind)
        kind = next((a for a in (hints[key], *typing.get_args(hints[key])) if _has_keys(a)), None)
        if kind is None:
            return []
    return [f.name for f in fields(kind)] if is_dataclass(kind) else list(kind.model_fields)


def _has_keys(kind) -> bool:
    return isinstance(kind, type) and (is_dataclass(kind) or issubclass(kind, BaseModel))


MOUNT_AGREEMENT_DEG = 1e-3  # rpy_deg and quaternion_xyzw given together must agree this closely


def rig_to_dict(rig: Rig) -> dict:
    """The YAML document of ``rig`` (camera inline)."""
    return {
        "name": rig.name,
        "camera": camera_to_kalibr(rig.camera, rig.name),
        "mount": {
            "position_m": [float(v) for v in rig.mount.position],
            "rpy_deg": [float(np.degrees(angle)) for angle in rig.mount.body_rpy],
        },
        "rate_hz": float(rig.rate_hz),
        "frame_id": rig.frame_id,
        "topics": {"image": rig.image_topic, "camera_info": rig.info_topic},
    }


def save_rig(path, rig: Rig) -> Path:
    """Write ``rig`` as a rig config YAML (to a temporary name, then renamed); return the path."""
    return write_text(path, yaml.safe_dump(rig_to_dict(rig), sort_keys=False, default_flow_style=None))


def load_rig(path) -> Rig:
    """The rig of a config YAML; errors name the file and the missing or bad field."""
    path = Path(path)
    return rig_from_config(read_config(path), path)


def rig_from_config(config: ConfigFile, path: Path) -> Rig:
    """The rig of the checked config file ``config``, read from ``path`` (a camchain is relative to it)."""
    return Rig(
        name=config.name,
        camera=_camera(config, path),
        mount=_mount(config.mount, path),
        rate_hz=config.rate_hz,
        image_topic=config.topics.image,
        info_topic=config.topics.camera_info,
        frame_id=config.frame_id,
    )


def _camera(config: ConfigFile, path: Path):
    if config.camera is not None:
        try:
            return camera_from_kalibr(config.camera.model_dump(exclude_none=True), f"{path}, camera")
        except ValueError as error:
            if str(path) in str(error):
                raise
            raise ValueError(f"{path}, camera: {error}") from None
    camchain = path.parent / config.camchain
    cameras = load_kalibr(camchain) if not camchain.is_dir() else {}
    if not cameras:
        raise ValueError(f"{path}: camchain {config.camchain} is a folder; expected a Kalibr camchain YAML file")
    name = config.camchain_camera or next(iter(cameras))
    if name not in cameras:
        raise ValueError(f"{path}: camchain_camera {name!r} is not in {config.camchain} ({', '.join(cameras)})")
    return cameras[name]


def load_mount(path) -> CameraMount:
    """The mount of the ``mount`` section of the YAML file ``path`` (a run config, or what ``gpo mount`` writes)."""
    path = Path(path)
    document = read_yaml(path)
    if not isinstance(document, dict) or "mount" not in document:
        raise ValueError(f"{path}: expected a YAML mapping with a mount section, as gpo mount writes it")
    try:
        section = MountSection.model_validate(document["mount"])
    except ValidationError as error:
        raise ValueError(f"{path}: " + "\n  ".join(_problem(e) for e in error.errors()[:8])) from None
    return _mount(section, path)


def _mount(section: MountSection, path: Path) -> CameraMount:
    """The mount of a config's ``mount`` section: ``position_m`` with ``rpy_deg`` (the body frame) or
    ``quaternion_xyzw`` (the optical frame); with both, they must agree within ``MOUNT_AGREEMENT_DEG``."""
    position = np.array(section.position_m)
    mounts = {}
    if section.rpy_deg is not None:
        mounts["rpy_deg"] = CameraMount.from_rpy(position, *np.radians(section.rpy_deg))
    if section.quaternion_xyzw is not None:
        mounts["quaternion_xyzw"] = CameraMount(position, Rotation.from_quat(section.quaternion_xyzw))
    if len(mounts) == 2:
        given, written = mounts["rpy_deg"], mounts["quaternion_xyzw"]
        angle = np.degrees((given.rotation.inv() * written.rotation).magnitude())
        if angle > MOUNT_AGREEMENT_DEG:
            as_rpy = [
                "[" + ", ".join(f"{round(np.degrees(angle), 3) + 0.0:.3f}" for angle in mount.body_rpy) + "]"
                for mount in (given, written)
            ]
            raise ValueError(
                f"{path}: mount rpy_deg and quaternion_xyzw disagree by {angle:.3f} degrees: as [roll, pitch, yaw] of "
                f"the body frame, rpy_deg is {as_rpy[0]} and quaternion_xyzw is {as_rpy[1]}; give one of them"
            )
    return mounts.get("rpy_deg", mounts.get("quaternion_xyzw"))

def load_camera(path) -> Camera:
    """The camera of a calibration file: a Basalt JSON (its first camera), a Kalibr camchain (its first camera) or a
    gpo run config (its ``camera``). Errors name the file."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no file {path}: expected a camera calibration (Kalibr YAML, Basalt JSON or config)")
    if path.suffix.lower() == ".json":
        return load_basalt(path)[0]
    document = read_yaml(path)
    if isinstance(document, dict) and "mount" in document and ("camera" in document or "camchain" in document):
        return load_rig(path).camera
    return next(iter(load_kalibr(path).values()))
