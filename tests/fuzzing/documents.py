"""Mutations of YAML and JSON files: the configs, calibrations and sweep specs of ``fuzzing.readers`` and a ROS 2
bag's ``metadata.yaml`` (``fuzzing.bags``).

A file is mutated as a document (a key deleted or renamed, an unknown key added, a value replaced by one of the wrong
type, NaN, infinity, a huge or tiny number, a list cut or doubled), as text (cut short, a line dropped, doubled,
moved or indented, a token of YAML's syntax put in, an alias bomb, a structure that holds itself, lists nested
thousands deep) or as bytes (``harness.byte_mutation``).
"""

from __future__ import annotations

import copy
import json
import math
from collections.abc import Callable
from pathlib import Path

import yaml
from hypothesis import strategies as st

from fuzzing.harness import Mutant, bytes_mutated

REPOSITORY = Path(__file__).resolve().parents[2]
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


def items_of(document):
    """(key, value) of a mapping, (index, value) of a list, nothing of anything else."""
    if isinstance(document, dict):
        return document.items()
    return enumerate(document) if isinstance(document, list) else ()


def _paths(document, prefix: tuple = ()) -> list[tuple]:
    """The path (keys and indices) to every node below ``document``."""
    found = []
    for key, value in items_of(document):
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


MUTATED = {".yaml": yaml_mutated, ".json": json_mutated}
"""How a file is mutated, by its suffix (others are left as they are)."""


@st.composite
def file_mutants(
    draw, seeds: dict[str, Mutant], most: int = 3, mutators: dict[str, Callable] | None = None
) -> Mutant:
    """A seed with up to ``most`` mutations, each of one of its files as its suffix says in ``mutators`` (default
    ``MUTATED``); none: the seed as it is."""
    mutators = MUTATED if mutators is None else mutators
    mutant = draw(st.sampled_from(list(seeds.values())))
    for _ in range(draw(st.integers(0, most))):
        name = draw(st.sampled_from([n for n, _ in mutant.files if Path(n).suffix in mutators]))
        mutant = draw(mutators[Path(name).suffix](mutant, name))
    return mutant


def seed(name: str, files: dict[str, bytes | str], entry: str) -> Mutant:
    """A seed called ``name``: its files (text or bytes, by name) and the one a reader is given."""
    return Mutant(name, tuple((n, c.encode() if isinstance(c, str) else c) for n, c in files.items()), entry)
