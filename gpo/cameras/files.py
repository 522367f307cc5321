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

Every model of ``gpo.cameras.MODELS`` says how these formats name it (``CameraModel.KALIBR_MODEL`` and its
neighbours); any other model is refused with an error that names it and the file.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Mapping, Sequence
from pathlib import Path

import yaml

from gpo.cameras import MODELS, CameraModel
from gpo.cameras.omni import Omni

Camera = CameraModel  # any model of ``gpo.cameras.MODELS``


def _field(entry: Mapping, key: str, where: str):
    if key not in entry:
        raise ValueError(f"{where}: missing the field '{key}'")
    return entry[key]


def load_kalibr(path) -> dict[str, Camera]:
    """Cameras of a Kalibr camchain YAML, by name (``cam0``, ...), in the file's order."""
    path = Path(path)
    document = yaml.safe_load(path.read_text())
    if not isinstance(document, Mapping) or not document:
        raise ValueError(f"{path}: not a Kalibr camchain (expected a mapping of cam0, cam1, ...)")
    return {name: camera_from_kalibr(entry, f"{path}, {name}") for name, entry in document.items()}


def camera_from_kalibr(entry: Mapping, where: str) -> Camera:
    """The camera of one Kalibr camchain entry (a mapping); ``where`` names it in error messages. The model is the one
    of ``MODELS`` whose ``KALIBR_MODEL``, ``KALIBR_DISTORTIONS`` and ``KALIBR_INTRINSICS`` the entry has."""
    model = _field(entry, "camera_model", where)
    intrinsics = [float(v) for v in _field(entry, "intrinsics", where)]
    width, height = _field(entry, "resolution", where)
    distortion = entry.get("distortion_model", "none")
    coeffs = [float(v) for v in entry.get("distortion_coeffs", []) or []]
    for cls in MODELS.values():
        form = (cls.KALIBR_MODEL, cls.KALIBR_INTRINSICS)
        if form == (model, len(intrinsics)) and distortion in cls.KALIBR_DISTORTIONS:
            return cls.from_kalibr(intrinsics, distortion, coeffs, width, height, where)
    forms = ", ".join(
        f"'{cls.KALIBR_MODEL}' ({cls.KALIBR_INTRINSICS} intrinsics, distortion "
        f"{' or '.join(map(repr, cls.KALIBR_DISTORTIONS))})"
        for cls in MODELS.values()
        if cls.KALIBR_MODEL is not None
    )
    raise ValueError(
        f"{where}: unsupported camera model '{model}' with distortion '{distortion}' and "
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
        basalt = _basalt_models()
        if model not in basalt:
            supported = ", ".join(map(repr, basalt))
            raise ValueError(f"{where}: unsupported camera model '{model}'; supported are {supported}")
        cls = basalt[model]
        values = _field(entry, "intrinsics", where)
        params = [float(_field(values, name, where)) for name in cls.PARAMETER_NAMES]
        cameras.append(cls.from_params(params, width, height))
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
        camera = cls.from_camera_info(model, d, fx, fy, cx, cy, width, height)
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
