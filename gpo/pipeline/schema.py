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
finite numbers, unknown keys at every level (with the nearest known one), and every number against the range a real
rig can have, with its unit (``gpo.motion.ranges``: one rule, one way of saying it). The ``klt``, ``keyframe``,
``fusion`` and ``features`` sections are the fields of ``KLTParameters``, ``KeyframePolicy``, ``FusionSettings`` and
``FeatureParameters`` themselves, which check their own ranges, so a field added there is a key of the file at once;
a key of the other sections is one line of its section below, its range in its type (``ranged``).
Errors name the file, the key and what is allowed; YAML errors name the line. The file is read by
``gpo.cameras.files.read_yaml``, which refuses a document whose aliases would expand beyond its limit (a "billion
laughs") before it is built.
"""

from __future__ import annotations

import difflib
import json
import typing
from dataclasses import fields, is_dataclass
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import yaml
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator
from scipy.spatial.transform import Rotation

from gpo.cameras.files import Camera, camera_from_kalibr, camera_to_kalibr, load_basalt, load_kalibr, read_yaml
from gpo.cameras.rig import CameraMount, Rig
from gpo.fusion import FusionSettings
from gpo.io.outputs import write_text
from gpo.motion.keyframes import KeyframePolicy
from gpo.motion.keypoints import FeatureParameters
from gpo.motion.klt import KLTParameters
from gpo.motion.ranges import MAX_IMAGE_PX, REACH_M, OutOfRange, check_value


def ranged(low, high, unit: str = "", whole: bool = False, low_open: bool = False):
    """A number of the file held to its range on a real rig, ``unit`` and all (``gpo.motion.ranges.check_value``):
    anything else (a flag, text, a number out of range, a fraction for a whole number) is refused with the range's
    words; a number given is read as a float, or an int when ``whole``."""

    def checked(value):
        check_value(value, low, high, unit, whole, low_open)
        return value if whole else float(value)

    return Annotated[Any, AfterValidator(checked)]


Name = Annotated[str, Field(min_length=1)]
Place = ranged(-REACH_M, REACH_M, " m")  # a coordinate in base_link
Height = ranged(0, 5, " m above the floor", low_open=True)
Angle = ranged(-360, 360, " deg")
Angles = tuple[Angle, Angle, Angle]
Component = ranged(-1, 1, ", a unit quaternion's component")


class Section(BaseModel):
    """A mapping of the file: its keys are its fields, nothing else; numbers finite."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class CameraSection(Section):
    """A Kalibr camchain entry (``gpo.cameras.files``); Kalibr's extrinsic keys are allowed and not read."""

    camera_model: Name
    intrinsics: list[float]
    distortion_model: str = "none"
    distortion_coeffs: list[float] | None = None
    resolution: tuple[ranged(1, MAX_IMAGE_PX, " px", whole=True), ranged(1, MAX_IMAGE_PX, " px", whole=True)]
    rostopic: str | None = None
    cam_overlaps: list[int] | None = None
    T_cam_imu: list[list[float]] | None = None
    T_cn_cnm1: list[list[float]] | None = None
    timeshift_cam_imu: float | None = None


class MountSection(Section):
    """The camera in base_link: ``position_m`` (metres) with ``rpy_deg`` (roll, pitch, yaw of the camera's body
    frame, degrees) or ``quaternion_xyzw`` (its optical frame), or both if they agree (``_mount``); ``height_m``,
    ``pitch_deg`` and ``roll_deg`` are for people and only checked."""

    position_m: tuple[Place, Place, Height]
    quaternion_xyzw: tuple[Component, Component, Component, Component] | None = None
    rpy_deg: Angles | None = None
    height_m: Height | None = None
    pitch_deg: Angle | None = None
    roll_deg: Angle | None = None

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

    squares: tuple[ranged(2, 100, " squares", whole=True), ranged(2, 100, " squares", whole=True)]
    square_m: ranged(0, 1, " m", low_open=True)
    margin_m: ranged(0, 1, " m")
    x_m: Place
    y_m: Place
    yaw_deg: Angle


class FloorImageSection(Section):
    """The floor image: extent (metres, base_link), pixel size, and the route that makes it (``gpo.pipeline``);
    unset keys take the pipeline's defaults."""

    x_range_m: tuple[Place, Place] | None = None
    y_range_m: tuple[Place, Place] | None = None
    metres_per_pixel: ranged(1e-5, 0.1, " m") | None = None
    route: str = "analytic"
    board_image: str | None = None
    board: BoardSection | None = None


class KinematicsSection(Section):
    """The paper's bicycle model (``gpo.odometry.kinematics.PaperBicycle``), metres."""

    wheelbase_m: ranged(0, 20, " m", low_open=True)
    rear_to_reference_m: ranged(0, 20, " m")


class OdometrySection(Section):
    method: str | None = None
    vector: str | None = None
    max_gap_s: ranged(0, 60, " s", low_open=True) | None = None


class ConfigFile(Section):
    """The whole file: the rig (``name``, ``camera`` or ``camchain``, ``mount``, ``rate_hz``, ``frame_id``,
    ``topics``) and the run's sections."""

    name: Name
    camera: CameraSection | None = None
    camchain: str | None = None
    camchain_camera: str | None = None
    mount: MountSection
    rate_hz: ranged(0, 1000, " Hz", low_open=True)
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


def read_config(path) -> ConfigFile:
    """The checked config file ``path`` (``ConfigFile``); a ValueError lists every problem, each with the key."""
    path = Path(path)
    return check_config(read_yaml(path), str(path))


def check_config(document, where: str) -> ConfigFile:
    """The checked config ``document`` (a YAML document: a file's, or one made by changing a file's); a ValueError
    names ``where`` it came from and lists every problem, each with the key."""
    if not isinstance(document, dict):
        keys = ", ".join(ConfigFile.model_fields)
        raise ValueError(f"{where}: a config is a YAML mapping of {keys}; got {type(document).__name__}")
    return checked(ConfigFile, document, where)


def checked(model: type[BaseModel], document, where: str, within: tuple = ()):
    """``document`` checked by ``model`` (``ConfigFile`` or one of its sections; ``within``: its keys from the top of
    a config file, or () for a document of its own) and built. Strictly, as YAML's scalars are typed: a flag is no
    number, a number no flag, text no number (the document is read as the JSON it is, in pydantic's strict mode). A
    ValueError names ``where`` it came from and lists every problem, each with its key."""
    try:
        text = json.dumps(document, default=str)
    except (TypeError, ValueError) as error:  # keys JSON cannot hold, a structure that holds itself
        raise ValueError(f"{where}: not a document of keys and values: {error}") from None
    try:
        return model.model_validate_json(text, strict=True)
    except ValidationError as error:
        root = ConfigFile if within else model
        problems = [_problem({**e, "loc": (*within, *e["loc"])}, root) for e in error.errors()[:8]]
        raise ValueError(f"{where}: " + "\n  ".join(problems)) from None


EXPECTED = {
    "float_type": "expected a number",
    "float_parsing": "expected a number",
    "int_type": "expected a whole number",
    "int_parsing": "expected a whole number",
    "int_from_float": "expected a whole number",
    "bool_type": "expected true or false",
    "bool_parsing": "expected true or false",
    "string_type": "expected text",
    "model_type": "expected a mapping of its keys",
    "dataclass_type": "expected a mapping of its keys",
    "dict_type": "expected a mapping of its keys",
    "tuple_type": "expected a list",
    "list_type": "expected a list",
    "finite_number": "expected a finite number",
}
"""What a key of the wrong type expected, by pydantic's error type."""


def _problem(error: dict, root: type) -> str:
    """One schema error as people read it: the key's path (its keys from the top of ``root``), what is wrong,
    what is allowed."""
    location = [part for part in error["loc"] if not isinstance(part, int)]
    where = ".".join(str(part) for part in error["loc"]) or "the file"
    cause = error.get("ctx", {}).get("error")
    if isinstance(cause, OutOfRange):  # a key of the file, or the keys of a section that checks its own
        return "\n  ".join(cause.lines(".".join(str(part) for part in error["loc"])))
    if error["type"] in ("extra_forbidden", "unexpected_keyword_argument"):
        known = _keys(location[:-1], root)
        close = difflib.get_close_matches(str(location[-1]), known, n=1)
        hint = f"did you mean {close[0]}? " if close else ""
        section = ".".join(map(str, location[:-1])) or "the file"
        return f"{where}: unknown key; {hint}the keys of {section} are {', '.join(known)}"
    message = EXPECTED.get(error["type"]) or error["msg"].removeprefix("Value error, ")
    if error["type"] == "missing":
        return f"{where}: missing; it is required"
    shown = repr(error["input"])
    return f"{where}: {message} (got {shown if len(shown) < 60 else shown[:57] + '...'})"


def _keys(location: list, root: type) -> list[str]:
    """The keys allowed at ``location`` (a list of keys from the top of ``root``)."""
    kind: Any = root
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


def rig_from_config(config: ConfigFile, path: Path, where: str | None = None) -> Rig:
    """The rig of the checked config file ``config``, read from ``path`` (a camchain is relative to it); errors name
    ``where`` it came from (default: ``path``)."""
    where = where or str(path)
    return Rig(
        name=config.name,
        camera=_camera(config, path, where),
        mount=_mount(config.mount, where),
        rate_hz=config.rate_hz,
        image_topic=config.topics.image,
        info_topic=config.topics.camera_info,
        frame_id=config.frame_id,
    )


def _camera(config: ConfigFile, path: Path, where: str):
    if config.camera is not None:
        try:
            return camera_from_kalibr(config.camera.model_dump(exclude_none=True), f"{where}, camera")
        except ValueError as error:
            if where in str(error):
                raise
            raise ValueError(f"{where}, camera: {error}") from None
    camchain = path.parent / config.camchain
    if camchain.is_dir():
        raise ValueError(f"{where}: camchain {config.camchain} is a folder; expected a Kalibr camchain YAML file")
    if not camchain.is_file():
        raise ValueError(
            f"{where}: camchain {config.camchain}: no file {camchain} (the key's path is relative to the config's "
            "folder); expected a Kalibr camchain YAML file: give its path, or the camera inline as camera"
        )
    try:
        document = read_yaml(camchain)
        entries = document if isinstance(document, dict) else {}
        name = config.camchain_camera or next(iter(entries), None)
        if name in entries:  # held to the ranges of a camera written inline, then read as one
            checked(CameraSection, entries[name], f"{where}: camchain {config.camchain}, {name}")
        cameras = load_kalibr(camchain)
    except (ValueError, OSError, yaml.YAMLError) as error:
        if where in str(error):
            raise
        raise ValueError(f"{where}: camchain {config.camchain}: {error}") from None
    if name not in cameras:
        raise ValueError(
            f"{where}: camchain_camera {name!r} is not in {config.camchain} ({', '.join(map(str, cameras))})"
        )
    return cameras[name]


def load_mount(path) -> CameraMount:
    """The mount of the ``mount`` section of the YAML file ``path`` (a run config, or what ``gpo mount`` writes)."""
    path = Path(path)
    document = read_yaml(path)
    if not isinstance(document, dict) or "mount" not in document:
        raise ValueError(f"{path}: expected a YAML mapping with a mount section, as gpo mount writes it")
    return _mount(checked(MountSection, document["mount"], str(path), ("mount",)), path)


def _mount(section: MountSection, where) -> CameraMount:
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
                f"{where}: mount rpy_deg and quaternion_xyzw disagree by {angle:.3f} degrees: as [roll, pitch, yaw] of "
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
