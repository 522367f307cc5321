"""The one folder where gpo keeps what it makes once and reads back, and the one way its files are named.

The folder is ``$GPO_CACHE_DIR`` when that is set, else the user's cache folder for gpo (``pooch.os_cache("gpo")``,
e.g. ``~/.cache/gpo``). Each kind of file has a subfolder of its own (``folder``): ``tables`` (the floor image's
remap tables, ``gpo.ground``), ``recordings`` (the simulated bags, ``gpo.sim.record``), ``runs`` (the floor runs
of the papers' tables), ``datasets`` (downloaded real files, ``gpo.datasets``, unless ``$GPO_DATA_DIR`` names a
folder of copies).

A file's name ends in its ``key``: the first 16 hex digits of the sha256 of everything it is made from, written as
canonical JSON, and of the source files that make it, so that a changed input or a changed program makes a new
file instead of reading a stale one. ``write`` makes a file under a name of its own (the process id) and renames it
into place, so processes sharing the folder never read one another's half-written files.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from collections.abc import Callable, Iterable
from pathlib import Path

import pooch

ENVIRONMENT_VARIABLE = "GPO_CACHE_DIR"
KINDS = ("tables", "recordings", "runs", "datasets")


def root() -> Path:
    """The cache folder: ``$GPO_CACHE_DIR``, else the user's cache folder for gpo."""
    return Path(os.environ.get(ENVIRONMENT_VARIABLE) or pooch.os_cache("gpo")).expanduser()


def folder(kind: str) -> Path:
    """The subfolder of the cache for files of ``kind`` (one of ``KINDS``)."""
    if kind not in KINDS:
        raise ValueError(f"unknown cache kind {kind!r}; the kinds are {', '.join(KINDS)}")
    return root() / kind


def key(*parts, sources: Iterable[Path] = ()) -> str:
    """16 hex digits of the sha256 of ``parts`` (JSON: numbers, strings, lists, dicts; anything else as its
    ``str``) and of the bytes of each file in ``sources``."""
    digest = hashlib.sha256(json.dumps(parts, sort_keys=True, default=str).encode())
    for source in sources:
        digest.update(Path(source).read_bytes())
    return digest.hexdigest()[:16]


def path(kind: str, name: str, file_key: str, suffix: str = "") -> Path:
    """The cache path ``<folder(kind)>/<name>-<file_key><suffix>``."""
    return folder(kind) / f"{name}-{file_key}{suffix}"


def write(target: Path, save: Callable[[Path], object]) -> Path:
    """Make ``target`` with ``save(partial)``, which writes a file (or a folder) at the path it is given: a name of
    this process's own beside ``target``, renamed to ``target`` once complete. When another process got there
    first, its file stays and this one's is removed (cached files of one name are identical). Returns ``target``."""
    target.parent.mkdir(parents=True, exist_ok=True)
    partial = target.with_name(f"{target.stem}-partial-{os.getpid()}{target.suffix}")
    _remove(partial)
    try:
        save(partial)
    except BaseException:
        _remove(partial)
        raise
    if target.exists():
        _remove(partial)
    else:
        partial.rename(target)
    return target


def _remove(path: Path) -> None:
    """Delete the file or folder ``path`` if it exists."""
    if path.is_dir():
        shutil.rmtree(path)
    elif path.exists():
        path.unlink()
