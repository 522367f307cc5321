"""Documents to fuzz the readers of text files with: run configs, calibrations (Kalibr, Basalt, ROS camera_info,
BoofCV), sweep specs and TUM trajectories.

A YAML or JSON file is mutated as a document (a key deleted or renamed, an unknown key added, a value replaced by
one of the wrong type, NaN, infinity, a huge or tiny number, a list cut or doubled) or as text (cut short, a line
dropped, doubled, moved or indented, a token of YAML's syntax put in, an alias bomb, a structure that holds itself),
or as bytes (``harness.byte_mutation``). A TUM file is mutated line by line and field by field, or as bytes.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import json
import math
import tempfile
from decimal import Decimal, InvalidOperation
from pathlib import Path

import numpy as np
import yaml
from hypothesis import strategies as st

from fuzzing.harness import Mutant, Target, bytes_mutated, parts
from gpo.batch.spec import load_spec
from gpo.cameras import KB4, T265_LIKE, CameraModel, DoubleSphere, Omni, Pinhole
from gpo.cameras.files import camera_from_camera_info, load_basalt, load_boofcv, load_kalibr, save_basalt, save_kalibr
from gpo.cli.evaluate import read_tum
from gpo.io.trajectory import Trajectory
from gpo.pipeline.config import config_to_dict, load_config, save_config
from gpo.pipeline.schema import load_camera, load_mount

REPOSITORY = Path(__file__).resolve().parents[2]
CONFIGS = REPOSITORY / "gpo" / "configs"
DATA = REPOSITORY / "data"

ODD_VALUES = st.one_of(
    st.sampled_from([
        None, True, False, "", "text", "0.6", 0, -1, 2**31, 2**64, 10**30, -(10**30), 1e308, -1e308, 5e-324,
        math.nan, math.inf, -math.inf, [], {}, [0.0], [1, 2, 3], {"x": 1}, "~", "null", "[1, 2",
    ]),
    st.floats(),
    st.integers(),
    st.text(max_size=12),
    st.lists(st.floats(), max_size=10),
    st.lists(st.integers(-(10**6), 10**6), max_size=10),
)
"""Values put where a document holds another."""

SYNTAX = ("- ", ": ", "&a ", "*a", "*b", "<<: *a", "!!python/object/apply:os.system ['true']", "!!binary x", "{", "}",
          "[", "]", "\t", "'", '"', "\x00", "\ufeff", "%YAML 1.1\n", "---\n", "...\n", "? ", "|", ">", "#", ",", "\\u",
          "!!float", "!!int", "!!str", "!!set", "!!omap", "=", "@", "`")
"""Tokens of YAML's syntax put into a file's text."""


def _items(document):
    """(key, value) of a mapping, (index, value) of a list, nothing of anything else."""
    if isinstance(document, dict):
        return document.items()
    return enumerate(document) if isinstance(document, list) else ()


def _paths(document, prefix: tuple = ()) -> list[tuple]:
    """The path (keys and indices) to every node below ``document``."""
    found = []
    for key, value in _items(document):
        found.append((*prefix, key))
        found.extend(_paths(value, (*prefix, key)))
    return found


def _walkable(document, budget: int = 20_000) -> bool:
    """Whether ``document`` holds neither itself (a YAML alias to a node around it) nor more than ``budget`` nodes
    once its aliases are followed: a document to mutate node by node."""
    count, stack = 0, [(document, frozenset())]
    while stack:
        node, within = stack.pop()
        count += 1
        if count > budget or id(node) in within:
            return False
        if isinstance(node, dict | list):
            values = node.values() if isinstance(node, dict) else node
            stack.extend((value, within | {id(node)}) for value in values if isinstance(value, dict | list))
    return True


def _parent(document, path: tuple):
    for key in path[:-1]:
        document = document[key]
    return document


@st.composite
def document_mutated(draw, document) -> tuple[object, str]:
    """``document`` (a copy) with one node deleted, replaced, renamed, added to, cut or doubled; what was done."""
    document = copy.deepcopy(document)
    paths = _paths(document)
    if not paths:
        return draw(ODD_VALUES), "the whole document replaced"
    path = draw(st.sampled_from(paths))
    parent, key = _parent(document, path), path[-1]
    kind = draw(st.sampled_from(("delete", "replace", "replace", "rename", "add", "cut", "double", "scale")))
    if kind == "delete":
        del parent[key]
    elif kind == "replace":
        parent[key] = draw(ODD_VALUES)
    elif kind == "rename" and isinstance(parent, dict):
        new = draw(st.one_of(st.text(max_size=12), st.just(str(key)[:-1]), st.just(f"{key}s"), st.integers()))
        parent[new] = parent.pop(key)
    elif kind == "add":
        target = parent[key] if isinstance(parent[key], dict) else parent
        if isinstance(target, dict):
            target[draw(st.text(min_size=1, max_size=12))] = draw(ODD_VALUES)
        else:
            target.append(draw(ODD_VALUES))
    elif kind in ("cut", "double") and isinstance(parent[key], list):
        items = parent[key]
        parent[key] = items[: draw(st.integers(0, len(items)))] if kind == "cut" else items * 2
    elif isinstance(parent[key], int | float) and not isinstance(parent[key], bool):
        parent[key] = parent[key] * draw(st.sampled_from((-1, 0, 1e-30, 1e6, 1e30, 1e300, math.nan)))
    else:
        parent[key] = draw(ODD_VALUES)
    return document, f"{kind} at {list(path)}"


def alias_bomb(width: int, depth: int) -> str:
    """A YAML "billion laughs": ``depth`` levels of lists holding ``width`` aliases of the level below."""
    lines = [f"l0: &l0 [{', '.join(['lol'] * width)}]"]
    lines += [f"l{k}: &l{k} [{', '.join([f'*l{k - 1}'] * width)}]" for k in range(1, depth + 1)]
    return "\n".join(lines) + "\n"


@st.composite
def text_mutated(draw, text: str) -> tuple[str, str]:
    """``text`` cut short, a line dropped, doubled, moved or indented, a syntax token put in, an alias bomb added or
    put in its place, a structure that holds itself, or lists nested thousands deep; what was done."""
    lines = text.splitlines(keepends=True) or [""]
    line = draw(st.integers(0, len(lines) - 1))
    kinds = ("cut", "drop", "double", "move", "indent", "token", "token", "bomb", "itself", "deep")
    kind = draw(st.sampled_from(kinds))
    if kind == "cut":
        at = draw(st.integers(0, len(text)))
        return text[:at], f"text cut at character {at}"
    if kind == "drop":
        return "".join(lines[:line] + lines[line + 1 :]), f"line {line + 1} dropped"
    if kind == "double":
        return "".join(lines[: line + 1] + lines[line:]), f"line {line + 1} doubled"
    if kind == "move":
        other = draw(st.integers(0, len(lines) - 1))
        lines[line], lines[other] = lines[other], lines[line]
        return "".join(lines), f"lines {line + 1} and {other + 1} swapped"
    if kind == "indent":
        spaces = draw(st.sampled_from(("  ", " ", "\t", "    ")))
        lines[line] = spaces + lines[line] if draw(st.booleans()) else lines[line].lstrip()
        return "".join(lines), f"line {line + 1} indented or dedented"
    if kind == "token":
        at = draw(st.integers(0, len(text)))
        token = draw(st.sampled_from(SYNTAX))
        return text[:at] + token + text[at:], f"{token!r} put in at character {at}"
    if kind == "bomb":
        bomb = alias_bomb(draw(st.integers(2, 12)), draw(st.integers(1, 12)))
        whole = draw(st.booleans())
        return (bomb if whole else text + "\n" + bomb), f"alias bomb {'in place of' if whole else 'after'} the text"
    if kind == "deep":
        at, depth = draw(st.integers(0, len(text))), draw(st.sampled_from((50, 500, 5000, 50_000)))
        return text[:at] + "[" * depth + "]" * depth + text[at:], f"{depth} nested lists put in at character {at}"
    return text + "\nitself: &itself [*itself, {loop: *itself}]\n", "a list that holds itself added"


@st.composite
def yaml_mutated(draw, mutant: Mutant, name: str) -> Mutant:
    """``mutant`` with its YAML file ``name`` mutated as a document, as text or as bytes."""
    content = mutant.content(name)
    kind = draw(st.sampled_from(("document", "document", "text", "bytes")))
    if kind == "document":
        try:
            document = yaml.safe_load(content)
        except (yaml.YAMLError, ValueError, RecursionError):  # already mutated past reading
            kind = "text"
        else:
            kind = kind if _walkable(document) else "text"
        if kind == "document":
            changed, step = draw(document_mutated(document))
            return mutant.replaced(name, yaml.safe_dump(changed, sort_keys=False).encode(), f"{name}: {step}")
    if kind == "text":
        changed, step = draw(text_mutated(content.decode("utf-8", errors="replace")))
        return mutant.replaced(name, changed.encode(), f"{name}: {step}")
    return draw(bytes_mutated(mutant, name=name))


@st.composite
def json_mutated(draw, mutant: Mutant, name: str) -> Mutant:
    """``mutant`` with its JSON file ``name`` mutated as a document, as text or as bytes."""
    content = mutant.content(name)
    kind = draw(st.sampled_from(("document", "document", "text", "bytes")))
    if kind == "document":
        try:
            document = json.loads(content)
        except (ValueError, RecursionError):
            kind = "text"
        else:
            kind = kind if _walkable(document) else "text"
        if kind == "document":
            changed, step = draw(document_mutated(document))
            return mutant.replaced(name, json.dumps(changed, indent=1).encode(), f"{name}: {step}")
    if kind == "text":
        changed, step = draw(text_mutated(content.decode("utf-8", errors="replace")))
        return mutant.replaced(name, changed.encode(), f"{name}: {step}")
    return draw(bytes_mutated(mutant, name=name))


@st.composite
def file_mutants(draw, seeds: dict[str, Mutant], most: int = 3) -> Mutant:
    """A seed with up to ``most`` mutations, each of one of its files as its suffix says (none: the seed as it is)."""
    mutant = draw(st.sampled_from(list(seeds.values())))
    for _ in range(draw(st.integers(0, most))):
        name = draw(st.sampled_from([n for n, _ in mutant.files if Path(n).suffix in MUTATED]))
        mutate = MUTATED[Path(name).suffix]
        mutant = draw(mutate(mutant, name))
    return mutant


def _seed(name: str, files: dict[str, bytes | str], entry: str) -> Mutant:
    return Mutant(name, tuple((n, c.encode() if isinstance(c, str) else c) for n, c in files.items()), entry)


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
        "sim_t265": _seed("sim_t265", {"rig.yaml": (CONFIGS / "sim_t265.yaml").read_bytes()}, "rig.yaml"),
        "sim_downward": _seed("sim_downward", {"rig.yaml": (CONFIGS / "sim_downward.yaml").read_bytes()}, "rig.yaml"),
        "camchain": _seed(
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
    return [found for key, value in _items(document) for found in _non_finite(value, (*path, key))]


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
        name: _seed(name, {"camchain.yaml": _written(
            save_kalibr, {f"cam{k}": cameras()[m] for k, m in enumerate(models)},
            {f"cam{k}": f"/cam{k}/image_raw" for k in range(len(models))})}, "camchain.yaml")
        for name, models in pairs.items()
    }


@functools.cache
def basalt_seeds() -> dict[str, Mutant]:
    chain = [cameras()[name] for name in ("eucm", "ds", "kb4")]
    return {"eucm+ds+kb4": _seed("eucm+ds+kb4", {"calib.json": _written(save_basalt, chain)}, "calib.json")}


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
    """Cameras finite, written back and read again as they were."""
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
    if isinstance(result["basalt"], list):
        check_cameras(result["basalt"])
        with tempfile.TemporaryDirectory() as folder:
            again = load_basalt(save_basalt(Path(folder) / "again.json", result["basalt"]))
        assert again == result["basalt"], "the cameras do not read back as written"
    check_cameras(_cameras_of(result["camera"]))


def check_boofcv(result, mutant: Mutant) -> None:
    check_cameras(_cameras_of(result))
    if not mutant.how:
        assert result == cameras()["omni"].__class__(398.8, 398.7, 319.2, 319.7, 1.13, (-0.25, 0.0097, 0.0, 0.0), 640,
                                                     720)


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
        seeds[name] = _seed(name, {"camera_info.json": json.dumps(fields)}, "camera_info.json")
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


# ------------------------------------------------------------------------------------------------ TUM files


TOKENS = ("nan", "inf", "-inf", "1e400", "-1e400", "1e30", "1e19", "9" * 30, "-1", "-0", "0x10", "1_000", "", "abc",
          "1.2.3", "+", "-", ".", "1e", "1e-400", "\u0661\u0662", "1,5", "1700000000.1234567891234", "+1.5e+3")
"""Fields put into a TUM line."""


@functools.cache
def tum_seeds() -> dict[str, Mutant]:
    """The first 30 poses of the sample's truth and of its tracking odometry (with its comment line)."""
    return {
        name: _seed(name, {"poses.tum": "".join((DATA / name).read_text().splitlines(keepends=True)[:31])}, "poses.tum")
        for name in ("sample_groundtruth.tum", "sample_tracking_odometry.tum")
    }


@st.composite
def tum_mutated(draw, mutant: Mutant, name: str) -> Mutant:
    """``mutant``'s TUM file with a line dropped, doubled or moved, a field replaced, added or taken away, its
    separators or line ends changed, or its bytes mutated."""
    kind = draw(st.sampled_from(("field", "field", "line", "separators", "text", "bytes")))
    if kind == "bytes":
        return draw(bytes_mutated(mutant, name=name))
    text = mutant.content(name).decode("utf-8", errors="replace")
    if kind == "text":
        changed, step = draw(text_mutated(text))
        return mutant.replaced(name, changed.encode(), f"{name}: {step}")
    lines = text.splitlines(keepends=True) or [""]
    at = draw(st.integers(0, len(lines) - 1))
    if kind == "field":
        fields = lines[at].split()
        token = draw(st.one_of(st.sampled_from(TOKENS), st.text(max_size=8), st.floats().map(repr)))
        where = draw(st.integers(0, len(fields)))
        how = draw(st.sampled_from(("replace", "add", "remove")))
        if how == "replace" and where < len(fields):
            fields[where] = token
        elif how == "remove" and where < len(fields):
            del fields[where]
        else:
            fields.insert(where, token)
        lines[at] = " ".join(fields) + "\n"
        step = f"line {at + 1}, field {where}: {how} {token!r}"
    elif kind == "line":
        other = draw(st.integers(0, len(lines) - 1))
        how = draw(st.sampled_from(("drop", "double", "swap")))
        if how == "drop":
            del lines[at]
        elif how == "double":
            lines.insert(at, lines[at])
        else:
            lines[at], lines[other] = lines[other], lines[at]
        step = f"line {at + 1}: {how} (with {other + 1})"
    else:
        separator = draw(st.sampled_from(("\t", ",", ", ", "  ", ";", "\r\n", "\r", "\x0c", "\u2028")))
        lines = [line.replace(" ", separator) if "\n" not in separator and "\r" not in separator
                 else line.rstrip("\n") + separator for line in lines]
        step = f"separators or line ends {separator!r}"
    return mutant.replaced(name, "".join(lines).encode(), f"{name}: {step}")


def _data_lines(content: bytes) -> list[list[str]]:
    """The fields of every line that is neither blank nor a comment, as Python splits text into lines and words."""
    text = content.decode("utf-8").replace("\r\n", "\n").replace("\r", "\n")
    lines = [line.strip() for line in text.splitlines()]
    return [line.replace(",", " ").split() for line in lines if line and not line.startswith("#")]


def _stamp_ns(text: str) -> Decimal:
    """A stamp in seconds as nanoseconds, by ``Decimal``; AssertionError for what is no number."""
    try:
        stamp = Decimal(text) * 10**9
    except InvalidOperation:
        raise AssertionError(f"the stamp {text!r} is no number, but was read") from None
    assert stamp.is_finite(), f"the stamp {text!r} is not finite, but was read"
    return stamp


def check_tum(trajectory: Trajectory, mutant: Mutant, once: bool = False) -> None:
    """Every pose line read, none skipped (``once``: of a pose repeated at one stamp, the first, as the command
    line's reader does); each number as Python's ``Decimal`` and ``float`` read it."""
    lines = _data_lines(mutant.content("poses.tum"))
    if once:
        lines = [fields for k, fields in enumerate(lines)
                 if k == 0 or int(_stamp_ns(fields[0])) != int(_stamp_ns(lines[k - 1][0]))]
    assert len(trajectory) == len(lines), f"{len(lines)} pose lines, {len(trajectory)} poses read"
    for k, fields in enumerate(lines):
        assert np.array_equal(trajectory.positions[k], [float(v) for v in fields[1:4]]), f"pose {k}: position"
        quaternion = np.array([float(v) for v in fields[4:8]])
        assert np.allclose(trajectory.quaternions[k], quaternion / np.linalg.norm(quaternion), rtol=0, atol=1e-12), (
            f"pose {k}: quaternion")
        stamp = _stamp_ns(fields[0])
        assert abs(Decimal(int(trajectory.stamps_ns[k])) - stamp) <= max(1, abs(stamp) * Decimal("1e-15")), (
            f"pose {k}: the stamp {fields[0]!r} was read as {trajectory.stamps_ns[k]} ns")


# ------------------------------------------------------------------------------------------------ the targets


MUTATED = {".yaml": yaml_mutated, ".json": json_mutated, ".tum": tum_mutated}
"""How a file is mutated, by its suffix (others are left as they are)."""

DOCUMENT_TARGETS = [
    Target("config", st.deferred(lambda: file_mutants(config_seeds())), read_config, check_config),
    Target("kalibr", st.deferred(lambda: file_mutants(kalibr_seeds())), read_kalibr, check_kalibr),
    Target("basalt", st.deferred(lambda: file_mutants(basalt_seeds())), read_basalt, check_basalt),
    Target("boofcv", st.deferred(lambda: file_mutants({"boofcv": _seed("boofcv", {"boofcv.yaml": BOOFCV},
                                                                       "boofcv.yaml")})), load_boofcv, check_boofcv),
    Target("camera_info", st.deferred(camera_info_mutants), read_camera_info, check_camera_info),
    Target("sweep spec", st.deferred(lambda: file_mutants({"spec": _seed("spec", {"spec.yaml": SPEC, "a.bag": b"x"},
                                                                         "spec.yaml")})), read_spec),
    Target("tum", st.deferred(lambda: file_mutants(tum_seeds())), Trajectory.read_tum, check_tum, names_file=False),
    Target("tum (evaluate)", st.deferred(lambda: file_mutants(tum_seeds())), read_tum,
           lambda trajectory, mutant: check_tum(trajectory, mutant, once=True)),
]
"""The readers of text files. ``Trajectory.read_tum`` leaves naming the file to its callers (the command line's
``read_tum`` names it)."""
