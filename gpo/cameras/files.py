"""Read and write camera calibrations in the formats of Kalibr, Basalt and ROS camera_info.

Kalibr camchain YAML (one block per camera, ``cam0``, ``cam1``, ...)::

    cam0:
      camera_model: eucm            # or ds, pinhole, omni
      intrinsics: [alpha, beta, fu, fv, pu, pv]   # ds: [xi, alpha, fu, fv, pu, pv]; pinhole: [fu, fv, pu, pv];
                                                  # omni: [xi, fu, fv, pu, pv]
      distortion_model: none        # pinhole: radtan, equidistant (Kannala-Brandt, KB4) or none; omni: radtan or none
      distortion_coeffs: []         # radtan: [k1, k2, r1, r2]; equidistant: [k1, k2, k3, k4]
      resolution: [width, height]
      rostopic: /cam0/image_raw

Basalt calibration JSON (cereal), ``camera_type`` eucm, ds or kb4::

    {"value0": {"intrinsics": [{"camera_type": "eucm",
                                "intrinsics": {"fx": ..., "fy": ..., "cx": ..., "cy": ...,
                                               "alpha": ..., "beta": ...}}, ...],   # ds: xi, alpha; kb4: k1..k4
                "resolution": [[width, height], ...], ...}}

ROS ``sensor_msgs/CameraInfo``: fx, fy, cx, cy in K (no skew) and ``distortion_model`` with D:
``plumb_bob`` (k1, k2, p1, p2[, k3]) or ``rational_polynomial`` with k4 = k5 = k6 = 0 as `Pinhole`;
``equidistant`` (k1, k2, k3, k4[, 0], as realsense-ros writes a T265's) as `KB4`; and this project's
conventions ``eucm`` (alpha, beta) and ``ds`` (xi, alpha).

BoofCV's camera YAML (``load_boofcv``), its unified model ``omnidirectional_universal``: ``pinhole`` (fx, fy,
cx, cy, width, height, skew), ``mirror_offset`` (xi), ``radial_tangential`` (``radial`` k1, k2; t1, t2 as
OpenCV's p1, p2), as `Omni`.

Every YAML file gpo reads (these calibrations, run configs, sweep specs) is read by ``read_yaml``: its size, its
encoding and its aliases checked before its document is built.

Every model of ``gpo.cameras.MODELS`` says how these formats name it (``CameraModel.KALIBR_MODEL`` and its
neighbours); any other model is refused with an error that names it and the file.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import yaml

from gpo.cameras import MODELS, CameraModel
from gpo.cameras.omni import Omni

Camera = CameraModel  # any model of ``gpo.cameras.MODELS``

MAX_BYTES = 1_000_000
"""The largest YAML or JSON file read (a config, a calibration, a sweep's spec), bytes."""
MAX_NODES = 100_000
"""The most YAML nodes a file may hold once its aliases are expanded."""
MAX_DEPTH = 100
"""The deepest a YAML file's lists and mappings written in brackets may nest (deeper, PyYAML takes seconds to find it
cannot build them)."""


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader, refusing brackets nested deeper than ``MAX_DEPTH`` as it meets them."""

    def fetch_flow_collection_start(self, TokenClass):
        if self.flow_level >= MAX_DEPTH:
            raise yaml.scanner.ScannerError(problem=f"lists or mappings nested deeper than {MAX_DEPTH}",
                                            problem_mark=self.get_mark())
        super().fetch_flow_collection_start(TokenClass)


def read_text(path, kind: str) -> str:
    """The text of the file ``path``, a ``kind`` (e.g. "YAML file"); errors name the file: a folder, missing, over
    ``MAX_BYTES``, not UTF-8."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{path} is a folder; expected a {kind}")
    if not path.is_file():
        raise FileNotFoundError(f"no file {path}: expected a {kind}")
    if path.stat().st_size > MAX_BYTES:
        raise ValueError(f"{path} is {path.stat().st_size} bytes; a {kind} here is at most {MAX_BYTES}")
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{path} is not a text file (UTF-8); expected a {kind}") from None


def read_yaml(path) -> Any:
    """The YAML document of the file ``path`` (a config, a calibration, a sweep's spec); errors name the file (and the
    line, for YAML errors). A document nested deeper than ``MAX_DEPTH``, or whose aliases would expand beyond
    ``MAX_NODES`` nodes (a "billion laughs"), is refused before it is built."""
    path = Path(path)
    text = read_text(path, "YAML file")
    loader = None
    try:
        loader = _Loader(text)  # checks the characters at once
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
    except RecursionError:
        raise ValueError(f"{path}: not valid YAML: nested too deeply") from None
    except (ValueError, TypeError, OverflowError) as error:  # a tagged value that cannot be built: !!int x, ...
        if str(path) in str(error):
            raise
        raise ValueError(f"{path}: not valid YAML: {error}") from None
    except (IndexError, KeyError, AttributeError):  # PyYAML's builders of an empty !!int, !!float, !!bool, !!timestamp
        raise ValueError(
            f"{path}: not valid YAML: a value tagged !!int, !!float, !!bool or !!timestamp is empty or not of its type"
        ) from None
    finally:
        if loader is not None:
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


def _shown(value) -> str:
    """``value`` as an error shows it: its repr, cut to 60 characters."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _field(entry, key: str, where: str):
    """``entry[key]`` of a mapping; errors name ``where``."""
    if not isinstance(entry, Mapping):
        raise ValueError(f"{where}: expected a mapping with the field '{key}', got {_shown(entry)}")
    if key not in entry:
        raise ValueError(f"{where}: missing the field '{key}'")
    return entry[key]


def _mapping(value, where: str) -> Mapping:
    """``value``, a mapping; errors name ``where``."""
    if not isinstance(value, Mapping):
        raise ValueError(f"{where}: expected a mapping, got {_shown(value)}")
    return value


def _list(value, where: str, length: int | None = None) -> list:
    """``value``, a list (of ``length`` items when given); errors name ``where``."""
    if not isinstance(value, list | tuple) or (length is not None and len(value) != length):
        items = "a list" if length is None else f"a list of {length}"
        raise ValueError(f"{where}: expected {items}, got {_shown(value)}")
    return list(value)


def _number(value, where: str) -> float:
    """``value`` as a float: a number, or text that reads as one (YAML 1.1 reads ``1e3`` as text); errors name
    ``where``."""
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise ValueError(f"{where}: expected a number, got {_shown(value)}")
    try:
        return float(value)
    except (ValueError, OverflowError):
        raise ValueError(f"{where}: expected a number, got {_shown(value)}") from None


def _numbers(values, where: str) -> list[float]:
    """``values``, a list of numbers (``_number``), as floats."""
    return [_number(value, where) for value in _list(values, where)]


def _named(error: ValueError, where: str) -> ValueError:
    """``error`` with ``where`` in front, unless it names it already."""
    return error if where in str(error) else ValueError(f"{where}: {error}")


def load_kalibr(path) -> dict[str, Camera]:
    """Cameras of a Kalibr camchain YAML, by name (``cam0``, ...), in the file's order."""
    path = Path(path)
    document = read_yaml(path)
    if not isinstance(document, Mapping) or not document:
        raise ValueError(f"{path}: not a Kalibr camchain (expected a mapping of cam0, cam1, ...)")
    return {name: camera_from_kalibr(entry, f"{path}, {name}") for name, entry in document.items()}


def camera_from_kalibr(entry: Mapping, where: str) -> Camera:
    """The camera of one Kalibr camchain entry (a mapping); ``where`` names it in error messages. The model is the one
    of ``MODELS`` whose ``KALIBR_MODEL``, ``KALIBR_DISTORTIONS`` and ``KALIBR_INTRINSICS`` the entry has."""
    model = _field(entry, "camera_model", where)
    intrinsics = _numbers(_field(entry, "intrinsics", where), f"{where}, intrinsics")
    width, height = _list(_field(entry, "resolution", where), f"{where}, resolution", 2)
    distortion = entry.get("distortion_model", "none")
    coeffs = _numbers(entry.get("distortion_coeffs", []) or [], f"{where}, distortion_coeffs")
    for cls in MODELS.values():
        form = (cls.KALIBR_MODEL, cls.KALIBR_INTRINSICS)
        if form == (model, len(intrinsics)) and distortion in cls.KALIBR_DISTORTIONS:
            try:
                return cls.from_kalibr(intrinsics, distortion, coeffs, width, height, where)
            except ValueError as error:
                raise _named(error, where) from None
    forms = ", ".join(
        f"'{cls.KALIBR_MODEL}' ({cls.KALIBR_INTRINSICS} intrinsics, distortion "
        f"{' or '.join(map(repr, cls.KALIBR_DISTORTIONS))})"
        for cls in MODELS.values()
        if cls.KALIBR_MODEL is not None
    )
    raise ValueError(
        f"{where}: unsupported camera model {_shown(model)} with distortion {_shown(distortion)} and "
        f"{len(intrinsics)} intrinsics; supported are {forms}"
    )


def camera_to_kalibr(camera: Camera, name: str) -> dict:
    """One Kalibr camchain entry (without ``rostopic``) for ``camera``; ``name`` names it in error messages."""
    if camera.KALIBR_MODEL is None:
        raise TypeError(f"{name}: cannot write a {type(camera).__name__} as a Kalibr camera")
    return _kalibr_entry(camera, camera.KALIBR_MODEL, *camera.kalibr(name))


def _kalibr_entry(camera: Camera, model: str, intrinsics: list, distortion: str, coeffs: list) -> dict:
    """A Kalibr camchain entry: its model, intrinsics and distortion, and the camera's resolution."""
    return {
        "camera_model": model,
        "intrinsics": intrinsics,
        "distortion_model": distortion,
        "distortion_coeffs": coeffs,
        "resolution": [camera.width, camera.height],
    }


def save_kalibr(
    path, cameras: Mapping[str, Camera], rostopics: Mapping[str, str] | None = None, comments: Sequence[str] = ()
) -> Path:
    """Write ``cameras`` (name -> camera) as a Kalibr camchain YAML; ``rostopics`` maps name -> topic; ``comments``
    are lines written first, each as a YAML comment (what a reader should know, such as a flagged calibration's
    warnings)."""
    document = {}
    for name, camera in cameras.items():
        document[name] = camera_to_kalibr(camera, name)
        if rostopics and name in rostopics:
            document[name]["rostopic"] = rostopics[name]
    path = Path(path)
    header = "".join(f"# {line}\n" for comment in comments for line in comment.splitlines())
    path.write_text(header + yaml.safe_dump(document, sort_keys=False, default_flow_style=None))
    return path


def _basalt_models() -> dict[str, type[CameraModel]]:
    """The models Basalt files hold, by their ``camera_type``."""
    return {cls.BASALT_TYPE: cls for cls in MODELS.values() if cls.BASALT_TYPE is not None}


def load_basalt(path) -> list[Camera]:
    """Cameras of a Basalt calibration JSON, in the file's order."""
    path = Path(path)
    try:
        document = json.loads(read_text(path, "Basalt calibration JSON"))
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not valid JSON ({error})") from None
    except RecursionError:
        raise ValueError(f"{path}: not valid JSON (nested too deeply)") from None
    calibration = _field(document, "value0", str(path))
    entries = _list(_field(calibration, "intrinsics", f"{path}, value0"), f"{path}, value0, intrinsics")
    sizes = _list(_field(calibration, "resolution", f"{path}, value0"), f"{path}, value0, resolution")
    if len(entries) != len(sizes):
        raise ValueError(f"{path}: {len(entries)} cameras in 'intrinsics' but {len(sizes)} in 'resolution'")
    cameras = []
    basalt = _basalt_models()
    for index, (entry, size) in enumerate(zip(entries, sizes, strict=True)):
        where = f"{path}, camera {index}"
        width, height = _list(size, f"{where}, resolution", 2)
        model = _field(entry, "camera_type", where)
        if not isinstance(model, str) or model not in basalt:
            supported = ", ".join(map(repr, basalt))
            raise ValueError(f"{where}: unsupported camera model {_shown(model)}; supported are {supported}")
        cls = basalt[model]
        values = _field(entry, "intrinsics", where)
        params = [_number(_field(values, name, where), f"{where}, {name}") for name in cls.PARAMETER_NAMES]
        try:
            cameras.append(cls.from_params(params, width, height))
        except ValueError as error:
            raise _named(error, where) from None
    return cameras


def save_basalt(path, cameras: Sequence[Camera], template: Mapping | None = None) -> Path:
    """Write ``cameras`` as a Basalt calibration JSON.

    Only the cameras' intrinsics and resolutions are written. Pass a loaded Basalt document as
    ``template`` to keep everything else it holds (camera-IMU extrinsics, IMU noise, ...): its
    intrinsics and resolutions are replaced, the rest is copied unchanged.
    """
    document = copy.deepcopy(dict(template)) if template is not None else {"value0": {}}
    calibration = document.setdefault("value0", {})
    intrinsics = []
    for index, camera in enumerate(cameras):
        if camera.BASALT_TYPE is None:
            known = ", ".join(cls.__name__ for cls in _basalt_models().values())
            raise TypeError(f"camera {index}: Basalt files hold {known} cameras, not a {type(camera).__name__}")
        values = dict(zip(camera.PARAMETER_NAMES, camera.params.tolist(), strict=True))
        intrinsics.append({"camera_type": camera.BASALT_TYPE, "intrinsics": values})
    calibration["intrinsics"] = intrinsics
    calibration["resolution"] = [[camera.width, camera.height] for camera in cameras]
    path = Path(path)
    path.write_text(json.dumps(document, indent=4))
    return path


def camera_from_camera_info(model: str, d, k, width: int, height: int, where: str) -> Camera:
    """The camera of a ROS camera_info's ``distortion_model``, D, K (9 values, row major) and image size;
    ``where`` names the message in error messages. The model is the first of ``MODELS`` that reads it."""
    if k[1] != 0.0:
        raise ValueError(f"{where}: the camera matrix K has a skew of {k[1]}; the camera models have none")
    fx, fy, cx, cy = (float(k[i]) for i in (0, 4, 2, 5))
    d = [float(v) for v in d]
    for cls in MODELS.values():
        try:
            camera = cls.from_camera_info(model, d, fx, fy, cx, cy, width, height)
        except ValueError as error:
            raise _named(error, where) from None
        if camera is not None:
            return camera
    expected = ", ".join(cls.CAMERA_INFO for cls in MODELS.values() if cls.CAMERA_INFO)
    raise ValueError(
        f"{where}: distortion model {model!r} with {len(d)} coefficients is not supported; expected one of {expected}"
    )


def camera_info_distortion(camera: Camera) -> tuple[str, list[float]]:
    """The camera_info ``distortion_model`` and D of ``camera`` (see the module docstring)."""
    return camera.camera_info_distortion()


def load_boofcv(path) -> Omni:
    """The camera of a BoofCV calibration YAML of the unified model (``model: omnidirectional_universal``)."""
    path = Path(path)
    document = read_yaml(path)
    if not isinstance(document, Mapping) or document.get("model") != "omnidirectional_universal":
        model = document.get("model") if isinstance(document, Mapping) else None
        raise ValueError(
            f"{path}: expected a BoofCV 'omnidirectional_universal' calibration, got model {_shown(model)}"
        )
    pinhole = _mapping(_field(document, "pinhole", str(path)), f"{path}, pinhole")
    skew = _number(pinhole.get("skew", 0.0), f"{path}, pinhole, skew")
    if skew != 0.0:
        raise ValueError(f"{path}: a skew of {skew}; the camera models have none")
    distortion = _mapping(_field(document, "radial_tangential", str(path)), f"{path}, radial_tangential")
    radial = _numbers(distortion.get("radial") or [], f"{path}, radial_tangential, radial")
    if len(radial) > 2:
        raise ValueError(f"{path}: {len(radial)} radial coefficients; the omni model holds two (k1, k2)")
    k1, k2 = (*radial, 0.0, 0.0)[:2]
    values = [_number(_field(pinhole, name, f"{path}, pinhole"), f"{path}, pinhole, {name}")
              for name in ("fx", "fy", "cx", "cy")]
    xi = _number(_field(document, "mirror_offset", str(path)), f"{path}, mirror_offset")
    tangential = [_number(distortion.get(name, 0.0), f"{path}, radial_tangential, {name}") for name in ("t1", "t2")]
    size = (_field(pinhole, "width", f"{path}, pinhole"), _field(pinhole, "height", f"{path}, pinhole"))
    try:
        return Omni(*values, xi, (k1, k2, *tangential), *size)
    except ValueError as error:
        raise _named(error, str(path)) from None
