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

Only the models of ``gpo.cameras`` are read; any other model is refused with an error that names
it and the file.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Mapping, Sequence
from pathlib import Path

import yaml

from gpo.cameras.double_sphere import DoubleSphere
from gpo.cameras.eucm import EUCM
from gpo.cameras.kb4 import KB4
from gpo.cameras.omni import Omni
from gpo.cameras.pinhole import Pinhole

Camera = EUCM | Pinhole | Omni | KB4 | DoubleSphere

#: Basalt's camera_type -> model, for the models both know
_BASALT_MODELS = {"eucm": EUCM, "ds": DoubleSphere, "kb4": KB4}


def _field(entry: Mapping, key: str, where: str):
    if key not in entry:
        raise ValueError(f"{where}: missing the field '{key}'")
    return entry[key]


def _radtan_coeffs(distortion: str, coeffs: list[float], where: str) -> tuple[float, ...]:
    """(k1, k2, p1, p2) of a 'radtan' entry, zeros for 'none'; ``where`` names the entry in error messages."""
    if distortion == "none":
        return (0.0, 0.0, 0.0, 0.0)
    if len(coeffs) != 4:
        raise ValueError(f"{where}: radtan needs 4 distortion_coeffs [k1, k2, r1, r2], got {len(coeffs)}")
    return tuple(coeffs)


def load_kalibr(path) -> dict[str, Camera]:
    """Cameras of a Kalibr camchain YAML, by name (``cam0``, ...), in the file's order."""
    path = Path(path)
    document = yaml.safe_load(path.read_text())
    if not isinstance(document, Mapping) or not document:
        raise ValueError(f"{path}: not a Kalibr camchain (expected a mapping of cam0, cam1, ...)")
    return {name: camera_from_kalibr(entry, f"{path}, {name}") for name, entry in document.items()}


def camera_from_kalibr(entry: Mapping, where: str) -> Camera:
    """The camera of one Kalibr camchain entry (a mapping); ``where`` names it in error messages."""
    model = _field(entry, "camera_model", where)
    intrinsics = [float(v) for v in _field(entry, "intrinsics", where)]
    width, height = _field(entry, "resolution", where)
    distortion = entry.get("distortion_model", "none")
    coeffs = [float(v) for v in entry.get("distortion_coeffs", []) or []]
    if model == "eucm" and distortion == "none" and len(intrinsics) == 6:
        alpha, beta, fx, fy, cx, cy = intrinsics
        return EUCM(fx, fy, cx, cy, alpha, beta, width, height)
    if model == "ds" and distortion == "none" and len(intrinsics) == 6:
        xi, alpha, fx, fy, cx, cy = intrinsics
        return DoubleSphere(fx, fy, cx, cy, xi, alpha, width, height)
    if model == "pinhole" and distortion == "equidistant" and len(intrinsics) == 4:
        if len(coeffs) != 4:
            raise ValueError(f"{where}: equidistant needs 4 distortion_coeffs [k1, k2, k3, k4], got {len(coeffs)}")
        return KB4(*intrinsics, *coeffs, width, height)
    if model == "pinhole" and distortion in ("radtan", "none") and len(intrinsics) == 4:
        return Pinhole(*intrinsics, _radtan_coeffs(distortion, coeffs, where), width, height)
    if model == "omni" and distortion in ("radtan", "none") and len(intrinsics) == 5:
        xi, fu, fv, pu, pv = intrinsics
        return Omni(fu, fv, pu, pv, xi, _radtan_coeffs(distortion, coeffs, where), width, height)
    raise ValueError(
        f"{where}: unsupported camera model '{model}' with distortion '{distortion}' and "
        f"{len(intrinsics)} intrinsics; supported are 'eucm' and 'ds' (6 intrinsics, distortion 'none'), "
        "'pinhole' (4 intrinsics, distortion 'radtan', 'equidistant' or 'none') and 'omni' (5 intrinsics, "
        "distortion 'radtan' or 'none')"
    )


def camera_to_kalibr(camera: Camera, name: str) -> dict:
    """One Kalibr camchain entry (without ``rostopic``) for ``camera``; ``name`` names it in error messages."""
    pinhole = [camera.fx, camera.fy, camera.cx, camera.cy]
    if isinstance(camera, EUCM):
        return _kalibr_entry(camera, "eucm", [camera.alpha, camera.beta, *pinhole], "none", [])
    if isinstance(camera, DoubleSphere):
        return _kalibr_entry(camera, "ds", [camera.xi, camera.alpha, *pinhole], "none", [])
    if isinstance(camera, KB4):
        return _kalibr_entry(camera, "pinhole", pinhole, "equidistant", list(camera.dist))
    if isinstance(camera, Pinhole):
        k1, k2, p1, p2, *rest = camera.dist
        if rest and rest[0] != 0.0:
            raise ValueError(f"{name}: Kalibr's radtan has no k3, but this camera has k3 = {rest[0]}")
        return _kalibr_entry(camera, "pinhole", pinhole, "radtan", [k1, k2, p1, p2])
    if isinstance(camera, Omni):
        return _kalibr_entry(camera, "omni", [camera.xi, *pinhole], "radtan", list(camera.dist))
    raise TypeError(f"{name}: cannot write a {type(camera).__name__} as a Kalibr camera")


def _kalibr_entry(camera: Camera, model: str, intrinsics: list, distortion: str, coeffs: list) -> dict:
    """A Kalibr camchain entry: its model, intrinsics and distortion, and the camera's resolution."""
    return {
        "camera_model": model,
        "intrinsics": intrinsics,
        "distortion_model": distortion,
        "distortion_coeffs": coeffs,
        "resolution": [camera.width, camera.height],
    }


def save_kalibr(path, cameras: Mapping[str, Camera], rostopics: Mapping[str, str] | None = None) -> Path:
    """Write ``cameras`` (name -> camera) as a Kalibr camchain YAML; ``rostopics`` maps name -> topic."""
    document = {}
    for name, camera in cameras.items():
        document[name] = camera_to_kalibr(camera, name)
        if rostopics and name in rostopics:
            document[name]["rostopic"] = rostopics[name]
    path = Path(path)
    path.write_text(yaml.safe_dump(document, sort_keys=False, default_flow_style=None))
    return path


def load_basalt(path) -> list[EUCM | DoubleSphere | KB4]:
    """Cameras of a Basalt calibration JSON, in the file's order."""
    path = Path(path)
    try:
        document = json.loads(path.read_text())
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not valid JSON ({error})") from None
    calibration = _field(document, "value0", str(path))
    entries = _field(calibration, "intrinsics", f"{path}, value0")
    sizes = _field(calibration, "resolution", f"{path}, value0")
    if len(entries) != len(sizes):
        raise ValueError(f"{path}: {len(entries)} cameras in 'intrinsics' but {len(sizes)} in 'resolution'")
    cameras = []
    for index, (entry, (width, height)) in enumerate(zip(entries, sizes, strict=True)):
        where = f"{path}, camera {index}"
        model = _field(entry, "camera_type", where)
        if model not in _BASALT_MODELS:
            raise ValueError(
                f"{where}: unsupported camera model '{model}'; supported are {', '.join(map(repr, _BASALT_MODELS))}"
            )
        cls = _BASALT_MODELS[model]
        values = _field(entry, "intrinsics", where)
        params = [float(_field(values, name, where)) for name in cls.PARAMETER_NAMES]
        cameras.append(cls.from_params(params, width, height))
    return cameras


def save_basalt(path, cameras: Sequence[EUCM | DoubleSphere | KB4], template: Mapping | None = None) -> Path:
    """Write ``cameras`` as a Basalt calibration JSON.

    Only the cameras' intrinsics and resolutions are written. Pass a loaded Basalt document as
    ``template`` to keep everything else it holds (camera-IMU extrinsics, IMU noise, ...): its
    intrinsics and resolutions are replaced, the rest is copied unchanged.
    """
    document = copy.deepcopy(dict(template)) if template is not None else {"value0": {}}
    calibration = document.setdefault("value0", {})
    intrinsics = []
    for index, camera in enumerate(cameras):
        names = [name for name, cls in _BASALT_MODELS.items() if type(camera) is cls]
        if not names:
            raise TypeError(
                f"camera {index}: Basalt files are written for EUCM, DoubleSphere and KB4 cameras, "
                f"got {type(camera).__name__}"
            )
        values = dict(zip(camera.PARAMETER_NAMES, camera.params.tolist(), strict=True))
        intrinsics.append({"camera_type": names[0], "intrinsics": values})
    calibration["intrinsics"] = intrinsics
    calibration["resolution"] = [[camera.width, camera.height] for camera in cameras]
    path = Path(path)
    path.write_text(json.dumps(document, indent=4))
    return path


def camera_from_camera_info(model: str, d, k, width: int, height: int, where: str) -> Camera:
    """The camera of a ROS camera_info's ``distortion_model``, D, K (9 values, row major) and image size;
    ``where`` names the message in error messages."""
    if k[1] != 0.0:
        raise ValueError(f"{where}: the camera matrix K has a skew of {k[1]}; the camera models have none")
    fx, fy, cx, cy = (float(k[i]) for i in (0, 4, 2, 5))
    d = [float(v) for v in d]
    if model == "eucm" and len(d) == 2:
        return EUCM(fx, fy, cx, cy, d[0], d[1], width, height)
    if model == "ds" and len(d) == 2:
        return DoubleSphere(fx, fy, cx, cy, d[0], d[1], width, height)
    if model == "equidistant" and (len(d) == 4 or (len(d) == 5 and d[4] == 0.0)):
        return KB4(fx, fy, cx, cy, *d[:4], width, height)
    if model == "rational_polynomial" and len(d) == 8 and not any(d[5:]):
        d = d[:5]
    if model in ("plumb_bob", "rational_polynomial") and len(d) in (0, 4, 5):
        return Pinhole(fx, fy, cx, cy, d or (0.0,) * 5, width, height)
    raise ValueError(
        f"{where}: distortion model {model!r} with {len(d)} coefficients is not supported; expected "
        "plumb_bob (k1, k2, p1, p2[, k3]), rational_polynomial with k4 = k5 = k6 = 0, equidistant "
        "(k1, k2, k3, k4), eucm (alpha, beta) or ds (xi, alpha)"
    )


def camera_info_distortion(camera: Camera) -> tuple[str, list[float]]:
    """The camera_info ``distortion_model`` and D of ``camera`` (see the module docstring)."""
    if isinstance(camera, EUCM):
        return "eucm", [camera.alpha, camera.beta]
    if isinstance(camera, DoubleSphere):
        return "ds", [camera.xi, camera.alpha]
    if isinstance(camera, KB4):
        return "equidistant", list(camera.dist)
    if isinstance(camera, Pinhole):
        return "plumb_bob", list(camera.dist)
    raise TypeError(f"a {type(camera).__name__} has no camera_info distortion model")


def load_boofcv(path) -> Omni:
    """The camera of a BoofCV calibration YAML of the unified model (``model: omnidirectional_universal``)."""
    path = Path(path)
    document = yaml.safe_load(path.read_text())
    if not isinstance(document, Mapping) or document.get("model") != "omnidirectional_universal":
        model = document.get("model") if isinstance(document, Mapping) else None
        raise ValueError(f"{path}: expected a BoofCV 'omnidirectional_universal' calibration, got model {model!r}")
    pinhole = _field(document, "pinhole", str(path))
    if float(pinhole.get("skew", 0.0)) != 0.0:
        raise ValueError(f"{path}: a skew of {pinhole['skew']}; the camera models have none")
    distortion = _field(document, "radial_tangential", str(path))
    radial = [float(k) for k in distortion.get("radial") or []]
    if len(radial) > 2:
        raise ValueError(f"{path}: {len(radial)} radial coefficients; the omni model holds two (k1, k2)")
    k1, k2 = (*radial, 0.0, 0.0)[:2]
    values = [float(_field(pinhole, name, f"{path}, pinhole")) for name in ("fx", "fy", "cx", "cy")]
    xi = float(_field(document, "mirror_offset", str(path)))
    tangential = (float(distortion.get("t1", 0.0)), float(distortion.get("t2", 0.0)))
    return Omni(*values, xi, (k1, k2, *tangential), pinhole["width"], pinhole["height"])
