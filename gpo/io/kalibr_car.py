"""The four surround-view fisheye cameras of Kalibr's car example, read from its ``pipeline.info``.

The V-Charge car "grobi" (ETH ASL, May 2013; images in `gpo.io.datasets.kalibr_car_images`) carries four
cameras calibrated with the unified model of Mei plus radial-tangential distortion (`gpo.cameras.Omni`).
Their calibration is a boost property-tree INFO file: the section ``grobi_cvg_may2013_second`` holds,
for camera i = 0..3 (front, left, rear, right, as the file's comments name them)::

    intrinsics<i> { projection { xi fu fv cu cv ru rv  distortion { k1 k2 p1 p2 } } }
    extrinsics<i> { T_v_c { q_a_b { x y z w }  t_a_b_a { x y z } } }

Frames: the vehicle frame v has x forward, y left, z up, in metres, with z = 0 about on the ground; its
origin lies about at the rear axle. ``t_a_b_a`` is the camera's optical centre in v. The quaternion
``q_a_b`` follows the JPL convention of Schweizer-Messer (``sm::kinematics``): the rotation vehicle <- optical
frame is the transpose of the matrix that the same four numbers give under Hamilton's convention::

    R_vc = R_hamilton(x, y, z, w)^T

(read literally as Hamilton the axes make no sense; read as JPL the front camera looks forward and the
side cameras look sideways and about 36 degrees down). Each camera's pose is a `gpo.cameras.rig.CameraMount`, the
pose of its optical frame (x right, y down, z forward) in the vehicle frame.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from gpo.cameras import Omni
from gpo.cameras.rig import CameraMount
from gpo.io import datasets

CAMERA_NAMES = ("front", "left", "rear", "right")
"""The cameras in the order of ``intrinsics0`` ... ``intrinsics3``, as the file's comments name them."""

CAR_SYSTEM = "grobi_cvg_may2013_second"
"""The section of ``pipeline.info`` that holds the car's camera system."""

_INFO_TOKEN = re.compile(r"\s*(?:(;.*)|([{}])|([^\s{};\"]+)|(\S))")


@dataclass(frozen=True, eq=False)
class CarCamera:
    """One camera of the car: its ``name``, its model ``camera`` and its ``mount``, the pose of its optical
    frame in the vehicle frame (position in metres, rotation vehicle <- optical)."""

    name: str
    camera: Omni
    mount: CameraMount


def kalibr_car_cameras() -> dict[str, CarCamera]:
    """The car's four cameras by name (front, left, rear, right), from the published ``pipeline.info``."""
    return read_pipeline_info(datasets.kalibr_car_pipeline_info())


def read_pipeline_info(path, system: str = CAR_SYSTEM) -> dict[str, CarCamera]:
    """The four cameras of the camera-system section ``system`` of a ``pipeline.info`` file, by name."""
    path = Path(path)
    tree = parse_info(path.read_text(), str(path))
    section = _subtree(tree, system, str(path))
    where = f"{path}, {system}"
    count = _number(section, "nCameras", where)
    if count != len(CAMERA_NAMES):
        raise ValueError(f"{where}: expected {len(CAMERA_NAMES)} cameras (nCameras), got {count:g}")
    return {
        name: CarCamera(
            name,
            _omni_camera(_subtree(section, f"intrinsics{index}", where), f"{where}, intrinsics{index}"),
            _mount(_subtree(section, f"extrinsics{index}", where), f"{where}, extrinsics{index}"),
        )
        for index, name in enumerate(CAMERA_NAMES)
    }


def _omni_camera(intrinsics: dict, where: str) -> Omni:
    """The `Omni` camera of an ``intrinsics<i>`` section (``projection`` with xi, fu, fv, cu, cv, ru, rv)."""
    projection = _subtree(intrinsics, "projection", where)
    where = f"{where}, projection"
    xi, fu, fv, cu, cv, ru, rv = (_number(projection, key, where) for key in ("xi", "fu", "fv", "cu", "cv", "ru", "rv"))
    distortion = _subtree(projection, "distortion", where)
    dist = tuple(_number(distortion, key, f"{where}, distortion") for key in ("k1", "k2", "p1", "p2"))
    return Omni(fx=fu, fy=fv, cx=cu, cy=cv, xi=xi, dist=dist, width=ru, height=rv)


def _mount(extrinsics: dict, where: str) -> CameraMount:
    """The pose of the optical frame in the vehicle frame from an ``extrinsics<i>`` section (``T_v_c``).

    The JPL quaternion q_a_b gives R_vc = R_hamilton(q)^T; t_a_b_a is the optical centre in metres.
    """
    transform = _subtree(extrinsics, "T_v_c", where)
    where = f"{where}, T_v_c"
    quaternion = _subtree(transform, "q_a_b", where)
    translation = _subtree(transform, "t_a_b_a", where)
    xyzw = [_number(quaternion, axis, f"{where}, q_a_b") for axis in "xyzw"]
    position = np.array([_number(translation, axis, f"{where}, t_a_b_a") for axis in "xyz"])
    return CameraMount(position, Rotation.from_quat(xyzw).inv())


def _subtree(tree: dict, key: str, where: str) -> dict:
    """The section ``key`` of ``tree``, else a ValueError naming ``where``."""
    value = tree.get(key)
    if not isinstance(value, dict):
        raise ValueError(f"{where}: missing the section '{key}'")
    return value


def _number(tree: dict, key: str, where: str) -> float:
    """The value of ``key`` in ``tree`` as a float, else a ValueError naming ``where``."""
    if key not in tree or isinstance(tree[key], dict):
        raise ValueError(f"{where}: missing the value '{key}'")
    try:
        return float(tree[key])
    except ValueError:
        raise ValueError(f"{where}: '{key}' must be a number, got {tree[key]!r}") from None


def parse_info(text: str, where: str) -> dict:
    """The tree of a boost property-tree INFO text: key -> value (str, "" when absent) or key -> subtree (dict).

    Each line holds ``key [value]``, optionally followed by ``{`` (on the same or the next line) that opens the
    key's children, closed by ``}``; ``;`` starts a comment. A key that has children keeps only them. Quoted
    strings, ``#include`` and repeated keys are not supported and raise a ValueError naming ``where`` and the line.
    """
    lines = enumerate(text.splitlines(), start=1)
    tokens = [(token, number) for number, line in lines for token in _tokens(line, where, number)]
    tree, _ = _parse_entries(tokens, 0, where, closing=False)
    return tree


def _tokens(line: str, where: str, number: int) -> list[str]:
    """The keys, values and braces of one INFO line, comments dropped."""
    tokens = []
    for comment, brace, word, other in _INFO_TOKEN.findall(line):
        if comment:
            break
        if other:
            raise ValueError(f"{where}, line {number}: unexpected {other!r} (quoted strings are not supported)")
        if brace or word:
            tokens.append(brace or word)
    return tokens


def _parse_entries(tokens: list[tuple[str, int]], start: int, where: str, closing: bool) -> tuple[dict, int]:
    """The entries from ``tokens[start]`` to the matching ``}`` (``closing``) or the end, and the index after."""
    tree: dict = {}
    index = start
    while index < len(tokens):
        key, line = tokens[index]
        if key == "}" and closing:
            return tree, index + 1
        if key in ("{", "}"):
            raise ValueError(f"{where}, line {line}: unexpected '{key}'")
        if key in tree:
            raise ValueError(f"{where}, line {line}: the key '{key}' is repeated")
        index += 1
        value: str | dict = ""
        if index < len(tokens) and tokens[index][1] == line and tokens[index][0] not in ("{", "}"):
            value, index = tokens[index][0], index + 1
        if index < len(tokens) and tokens[index][1] == line and tokens[index][0] not in ("{", "}"):
            raise ValueError(f"{where}, line {line}: more than a key and a value")
        if index < len(tokens) and tokens[index][0] == "{":
            value, index = _parse_entries(tokens, index + 1, where, closing=True)
        tree[key] = value
    if closing:
        raise ValueError(f"{where}: a '{{' is never closed")
    return tree, index
