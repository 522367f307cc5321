"""One YAML file describes a rig: its camera, where the camera sits on the robot, and its topics.

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

Later chapters add their own sections (the floor image, the motion estimator, the kinematic
model); ``load_rig`` reads the rig and leaves them alone.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from gpo.calibfiles import camera_from_kalibr, camera_to_kalibr, load_kalibr
from gpo.rig import CameraMount, Rig

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
    """Write ``rig`` as a rig config YAML; return the path."""
    path = Path(path)
    path.write_text(yaml.safe_dump(rig_to_dict(rig), sort_keys=False, default_flow_style=None))
    return path


def load_rig(path) -> Rig:
    """The rig of a config YAML; errors name the file and the missing or bad field."""
    path = Path(path)
    document = yaml.safe_load(path.read_text())
    if not isinstance(document, Mapping):
        raise ValueError(f"{path}: a rig config is a YAML mapping with name, camera, mount, rate_hz, frame_id, topics")
    camera = _camera(document, path)
    mount = _mount(_section(document, "mount", path), path)
    topics = _section(document, "topics", path)
    return Rig(
        name=str(_field(document, "name", path)),
        camera=camera,
        mount=mount,
        rate_hz=float(_field(document, "rate_hz", path)),
        image_topic=str(_field(topics, "image", path, "topics")),
        info_topic=str(topics.get("camera_info", "")),
        frame_id=str(_field(document, "frame_id", path)),
    )


def _mount(section: Mapping, path: Path) -> CameraMount:
    """The mount of a config's ``mount`` section: ``position_m`` with ``rpy_deg`` (the body frame) or
    ``quaternion_xyzw`` (the optical frame); with both, they must agree within ``MOUNT_AGREEMENT_DEG``."""
    position = np.asarray(_field(section, "position_m", path, "mount"), dtype=float)
    if position.shape != (3,) or not np.isfinite(position).all():
        raise ValueError(f"{path}: mount position_m must be 3 finite numbers (x, y, z metres in base_link)")
    if "rpy_deg" not in section and "quaternion_xyzw" not in section:
        raise ValueError(
            f"{path}: 'mount' has no 'rpy_deg': give rpy_deg: [roll, pitch, yaw] in degrees (the camera's body frame, "
            "x forward, y left, z up, in base_link) or quaternion_xyzw (its optical frame)"
        )
    mounts = {}
    if "rpy_deg" in section:
        rpy = np.asarray(section["rpy_deg"], dtype=float)
        if rpy.shape != (3,) or not np.isfinite(rpy).all():
            raise ValueError(f"{path}: mount rpy_deg must be 3 finite numbers [roll, pitch, yaw] in degrees")
        mounts["rpy_deg"] = CameraMount.from_rpy(position, *np.radians(rpy))
    if "quaternion_xyzw" in section:
        quaternion = np.asarray(section["quaternion_xyzw"], dtype=float)
        if quaternion.shape != (4,) or not np.isfinite(quaternion).all() or np.linalg.norm(quaternion) < 1e-9:
            raise ValueError(f"{path}: mount quaternion_xyzw must be 4 finite numbers, not all zero")
        mounts["quaternion_xyzw"] = CameraMount(position, Rotation.from_quat(quaternion))
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


def _camera(document: Mapping, path: Path):
    if "camera" in document:
        return camera_from_kalibr(document["camera"], f"{path}, camera")
    if "camchain" in document:
        cameras = load_kalibr(path.parent / document["camchain"])
        name = document.get("camchain_camera", next(iter(cameras)))
        if name not in cameras:
            raise ValueError(
                f"{path}: camchain_camera {name!r} is not in {document['camchain']} ({', '.join(cameras)})"
            )
        return cameras[name]
    raise ValueError(f"{path}: no camera: give 'camera' (a Kalibr camchain entry) or 'camchain' (a camchain file)")


def _section(document: Mapping, key: str, path: Path) -> Mapping:
    section = _field(document, key, path)
    if not isinstance(section, Mapping):
        raise ValueError(f"{path}: '{key}' must be a mapping")
    return section


def _field(section: Mapping, key: str, path: Path, within: str | None = None):
    if key not in section:
        place = f"'{within}'" if within else "the file"
        raise ValueError(f"{path}: {place} has no '{key}'")
    return section[key]
