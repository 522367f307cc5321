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
    mount:                         # the camera's optical frame in base_link
      position_m: [0.6, 0.0, 0.12]
      quaternion_xyzw: [...]
      height_m: 0.12               # for people; position_m and quaternion_xyzw are what is read
      pitch_deg: 6.0
      roll_deg: 1.5
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


def rig_to_dict(rig: Rig) -> dict:
    """The YAML document of ``rig`` (camera inline)."""
    pitch, roll = np.degrees(rig.mount.body_rotation.as_euler("YXZ")[:2])
    return {
        "name": rig.name,
        "camera": camera_to_kalibr(rig.camera, rig.name),
        "mount": {
            "position_m": [float(v) for v in rig.mount.position],
            "quaternion_xyzw": [float(v) for v in rig.mount.rotation.as_quat()],
            "height_m": round(rig.mount.height, 6),
            "pitch_deg": round(float(pitch), 6),
            "roll_deg": round(float(roll), 6),
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
    mount = _section(document, "mount", path)
    position = np.asarray(_field(mount, "position_m", path, "mount"), dtype=float)
    quaternion = np.asarray(_field(mount, "quaternion_xyzw", path, "mount"), dtype=float)
    if position.shape != (3,) or quaternion.shape != (4,) or np.linalg.norm(quaternion) < 1e-9:
        raise ValueError(f"{path}: mount needs position_m (3 numbers, metres) and quaternion_xyzw (4 numbers)")
    topics = _section(document, "topics", path)
    return Rig(
        name=str(_field(document, "name", path)),
        camera=camera,
        mount=CameraMount(position, Rotation.from_quat(quaternion)),
        rate_hz=float(_field(document, "rate_hz", path)),
        image_topic=str(_field(topics, "image", path, "topics")),
        info_topic=str(topics.get("camera_info", "")),
        frame_id=str(_field(document, "frame_id", path)),
    )


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
