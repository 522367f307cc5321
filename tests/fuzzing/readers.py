"""The readers of configs, calibrations (Kalibr, Basalt, BoofCV, ROS camera_info) and sweep specs, each with its
seeds and what a correct result is.

The seeds are the shipped configs (one with its camera in a Kalibr camchain beside it), calibrations written by
gpo's own writers for a camera of every model, a BoofCV file of the form BoofCV writes, a sweep spec of every kind of
source; they are mutated as ``fuzzing.documents`` says. camera_info's fields are changed within their message types
(a bag's reader gives no others). A result is correct when its numbers are finite and it reads back as it writes.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import tempfile
from pathlib import Path

import numpy as np
import yaml
from hypothesis import strategies as st

from fuzzing.documents import REPOSITORY, file_mutants, items_of, seed
from fuzzing.harness import Mutant, Target, parts
from gpo.batch.spec import load_spec
from gpo.cameras import KB4, T265_LIKE, CameraModel, DoubleSphere, Omni, Pinhole
from gpo.cameras.files import camera_from_camera_info, load_basalt, load_boofcv, load_kalibr, save_basalt, save_kalibr
from gpo.pipeline.config import config_to_dict, load_config, save_config
from gpo.pipeline.schema import load_camera, load_mount

CONFIGS = REPOSITORY / "gpo" / "configs"


# ------------------------------------------------------------------------------------------------ configs


def _camchain_config() -> str:
    """The shipped T265 config with its camera in a Kalibr camchain beside it."""
    document = yaml.safe_load((CONFIGS / "sim_t265.yaml").read_text())
    del document["camera"]
    document["camchain"], document["camchain_camera"] = "camchain.yaml", "cam1"
    return yaml.safe_dump(document, sort_keys=False)


@functools.cache
def config_seeds() -> dict[str, Mutant]:
    return {
        "sim_t265": seed("sim_t265", {"rig.yaml": (CONFIGS / "sim_t265.yaml").read_bytes()}, "rig.yaml"),
        "sim_downward": seed("sim_downward", {"rig.yaml": (CONFIGS / "sim_downward.yaml").read_bytes()}, "rig.yaml"),
        "camchain": seed(
            "camchain",
            {"rig.yaml": _camchain_config(), "camchain.yaml": kalibr_seeds()["eucm+ds"].content("camchain.yaml")},
            "rig.yaml",
        ),
    }


def read_config(path: Path) -> dict[str, object]:
    """The run config, its mount and its camera, each read on its own."""
    return parts({"config": lambda: load_config(path), "mount": lambda: load_mount(path),
                  "camera": lambda: load_camera(path)})


def check_config(result: dict[str, object], mutant: Mutant) -> None:
    """A config read is one with finite numbers, which its own written form reads back as."""
    config = result["config"]
    if not hasattr(config, "rig"):
        return
    document = yaml.safe_load(mutant.content("rig.yaml"))
    assert not _non_finite(document), f"a config with {_non_finite(document)} was read"
    if "camchain" in config_to_dict(config):
        return
    with tempfile.TemporaryDirectory() as folder:
        again = load_config(save_config(Path(folder) / "again.yaml", config))
    assert _close(config_to_dict(again), config_to_dict(config)), "the config does not read back as it was written"


def _close(one, other) -> bool:
    """Whether two documents are equal, their numbers to 1e-9 (an orientation written as angles and read back)."""
    if isinstance(one, float | int) and isinstance(other, float | int) and not isinstance(one, bool):
        return math.isclose(one, other, rel_tol=1e-9, abs_tol=1e-9)
    if isinstance(one, dict) and isinstance(other, dict):
        return one.keys() == other.keys() and all(_close(one[k], other[k]) for k in one)
    if isinstance(one, list | tuple) and isinstance(other, list | tuple):
        return len(one) == len(other) and all(_close(a, b) for a, b in zip(one, other, strict=True))
    return one == other


def _non_finite(document, path: tuple = ()) -> list:
    """The paths to the non-finite numbers in ``document``."""
    if isinstance(document, float) and not math.isfinite(document):
        return [list(path)]
    return [found for key, value in items_of(document) for found in _non_finite(value, (*path, key))]


# ------------------------------------------------------------------------------------------------ calibrations


@functools.cache
def cameras() -> dict[str, CameraModel]:
    """A camera of every model, near the T265's fisheye (the omni model as BoofCV's example has it)."""
    return {
        "eucm": T265_LIKE,
        "ds": DoubleSphere(286.0, 286.0, 424.0, 400.0, -0.2, 0.6, 848, 800),
        "kb4": KB4.from_params([286.0, 286.0, 424.0, 400.0, 0.01, -0.002, 0.001, -0.0001], 848, 800),
        "omni": Omni(398.8, 398.8, 319.2, 319.7, 1.13, (-0.25, 0.0097, 0.0, 0.0), 640, 720),
        "pinhole": Pinhole(286.0, 287.0, 424.0, 400.0, (0.01, -0.002, 0.0001, 0.0002), 848, 800),
    }


def _written(save, *arguments) -> bytes:
    with tempfile.TemporaryDirectory() as folder:
        return save(Path(folder) / "file", *arguments).read_bytes()


@functools.cache
def kalibr_seeds() -> dict[str, Mutant]:
    pairs = {"eucm+ds": ("eucm", "ds"), "kb4+omni": ("kb4", "omni"), "pinhole": ("pinhole",)}
    return {
        name: seed(name, {"camchain.yaml": _written(
            save_kalibr, {f"cam{k}": cameras()[m] for k, m in enumerate(models)},
            {f"cam{k}": f"/cam{k}/image_raw" for k in range(len(models))})}, "camchain.yaml")
        for name, models in pairs.items()
    }


@functools.cache
def basalt_seeds() -> dict[str, Mutant]:
    chain = [cameras()[name] for name in ("eucm", "ds", "kb4")]
    return {"eucm+ds+kb4": seed("eucm+ds+kb4", {"calib.json": _written(save_basalt, chain)}, "calib.json")}


BOOFCV = """# Omnidirectional camera model with radial and tangential distortion
pinhole:
  fx: 398.8
  fy: 398.7
  cx: 319.2
  cy: 319.7
  width: 640
  height: 720
  skew: 0.0
model: omnidirectional_universal
radial_tangential:
  radial:
  - -0.25
  - 0.0097
  t1: 0.0
  t2: 0.0
version: 0
mirror_offset: 1.13
"""


def _cameras_of(result) -> list[CameraModel]:
    values = result.values() if isinstance(result, dict) else result if isinstance(result, list) else [result]
    return [value for value in values if isinstance(value, CameraModel)]


def check_cameras(found: list[CameraModel]) -> None:
    """Every number of every camera finite."""
    for camera in found:
        numbers = np.hstack([np.ravel(value) for value in dataclasses.asdict(camera).values()]).astype(float)
        assert np.isfinite(numbers).all(), f"{camera!r} is not finite"


def read_kalibr(path: Path) -> dict[str, object]:
    return parts({"kalibr": lambda: load_kalibr(path), "camera": lambda: load_camera(path)})


def check_kalibr(result: dict[str, object], mutant: Mutant) -> None:
    """Cameras finite, written back and read again as they were; a seed's, the cameras it was written of."""
    if not mutant.how:
        assert list(result["kalibr"].values()) == [cameras()[model] for model in mutant.seed.split("+")]
    if isinstance(result["kalibr"], dict):
        check_cameras(_cameras_of(result["kalibr"]))
        assert load_kalibr_again(result["kalibr"]) == result["kalibr"], "the cameras do not read back as written"
    check_cameras(_cameras_of(result["camera"]))


def load_kalibr_again(found: dict[str, CameraModel]) -> dict[str, CameraModel]:
    with tempfile.TemporaryDirectory() as folder:
        return load_kalibr(save_kalibr(Path(folder) / "again.yaml", found))


def read_basalt(path: Path) -> dict[str, object]:
    return parts({"basalt": lambda: load_basalt(path), "camera": lambda: load_camera(path)})


def check_basalt(result: dict[str, object], mutant: Mutant) -> None:
    """Cameras finite, written back and read again as they were; a seed's, the cameras it was written of."""
    if not mutant.how:
        assert result["basalt"] == [cameras()[model] for model in mutant.seed.split("+")]
    if isinstance(result["basalt"], list):
        check_cameras(result["basalt"])
        with tempfile.TemporaryDirectory() as folder:
            again = load_basalt(save_basalt(Path(folder) / "again.json", result["basalt"]))
        assert again == result["basalt"], "the cameras do not read back as written"
    check_cameras(_cameras_of(result["camera"]))


def check_boofcv(result, mutant: Mutant) -> None:
    """A camera finite; the seed's, the numbers ``BOOFCV`` holds."""
    check_cameras(_cameras_of(result))
    if not mutant.how:
        assert result == Omni(398.8, 398.7, 319.2, 319.7, 1.13, (-0.25, 0.0097, 0.0, 0.0), 640, 720)


@functools.cache
def camera_info_seeds() -> dict[str, Mutant]:
    """camera_info messages' fields (distortion_model, D, K, width, height) as JSON, of every model it holds."""
    seeds = {}
    for name, camera in cameras().items():
        if not camera.CAMERA_INFO:
            continue
        model, d = camera.camera_info_distortion()
        k = [camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0]
        fields = {"distortion_model": model, "d": d, "k": k, "width": camera.width, "height": camera.height}
        seeds[name] = seed(name, {"camera_info.json": json.dumps(fields)}, "camera_info.json")
    return seeds


FLOATS = st.one_of(st.floats(), st.sampled_from((0.0, -0.0, 1e308, -1e308, 5e-324, math.nan, math.inf, -math.inf)))


@st.composite
def camera_info_mutants(draw) -> Mutant:
    """A seed's fields changed within their message types: another model name, D longer, shorter or changed, a K
    entry changed, another image size."""
    mutant = draw(st.sampled_from(list(camera_info_seeds().values())))
    fields = json.loads(mutant.content("camera_info.json"))
    steps = []
    for _ in range(draw(st.integers(0, 3))):
        kind = draw(st.sampled_from(("model", "d", "d size", "k", "size")))
        if kind == "model":
            fields["distortion_model"] = draw(st.one_of(st.sampled_from(
                ("eucm", "ds", "equidistant", "plumb_bob", "rational_polynomial", "fisheye", "", "EUCM")),
                st.text(max_size=10)))
        elif kind == "d" and fields["d"]:
            fields["d"][draw(st.integers(0, len(fields["d"]) - 1))] = draw(FLOATS)
        elif kind == "d size":
            fields["d"] = draw(st.lists(FLOATS, max_size=14))
        elif kind == "k":
            fields["k"][draw(st.integers(0, 8))] = draw(FLOATS)
        else:
            fields[draw(st.sampled_from(("width", "height")))] = draw(st.integers(0, 2**32 - 1))
        steps.append(f"{kind}: {fields}")
    return Mutant(mutant.seed, (("camera_info.json", json.dumps(fields).encode()),), mutant.entry, tuple(steps))


def read_camera_info(path: Path) -> CameraModel:
    fields = json.loads(path.read_text())
    return camera_from_camera_info(fields["distortion_model"], fields["d"], fields["k"], fields["width"],
                                   fields["height"], str(path))


def check_camera_info(camera: CameraModel, mutant: Mutant) -> None:
    """A camera finite, and its own camera_info read back as it."""
    check_cameras([camera])
    model, d = camera.camera_info_distortion()
    k = [camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0]
    assert camera_from_camera_info(model, d, k, camera.width, camera.height, "again") == camera


# ------------------------------------------------------------------------------------------------ sweep specs


SPEC = """recordings:
  - file: a.bag
    label: hall
  - glob: '*.bag'
  - preset: test
    seeds: [1, 2]
config: rig.yaml
set: {odometry.vector: median}
vary:
  klt.window_px: [15, 21]
  odometry.method: [gpo, gpo-exact]
runs: [{klt.max_corners: 100}, {klt.max_corners: 200}]
truth_topic: /mocap/base_link
topic: null
"""


def read_spec(path: Path) -> dict[str, object]:
    spec = load_spec(path)
    return parts({"spec": lambda: spec, "runs": lambda: spec.expand(dict.fromkeys(spec.presets(), "x.bag"))})


# ------------------------------------------------------------------------------------------------ the targets


READER_TARGETS = [
    Target("config", st.deferred(lambda: file_mutants(config_seeds())), read_config, check_config),
    Target("kalibr", st.deferred(lambda: file_mutants(kalibr_seeds())), read_kalibr, check_kalibr),
    Target("basalt", st.deferred(lambda: file_mutants(basalt_seeds())), read_basalt, check_basalt),
    Target("boofcv", st.deferred(lambda: file_mutants({"boofcv": seed("boofcv", {"boofcv.yaml": BOOFCV},
                                                                      "boofcv.yaml")})), load_boofcv, check_boofcv),
    Target("camera_info", st.deferred(camera_info_mutants), read_camera_info, check_camera_info),
    Target("sweep spec", st.deferred(lambda: file_mutants({"spec": seed("spec", {"spec.yaml": SPEC, "a.bag": b"x"},
                                                                        "spec.yaml")})), read_spec),
]
"""The readers of configs, calibrations and sweep specs."""
