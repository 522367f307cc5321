"""The one folder where gpo keeps what it makes once and reads back, and the one way its files are named.

The folder is ``$GPO_CACHE_DIR`` when that is set, else the user's cache folder for gpo (``pooch.os_cache("gpo")``,
e.g. ``~/.cache/gpo``). Each kind of file has a subfolder of its own (``folder``): ``tables`` (the floor image's
remap tables, ``gpo.floor_image``), ``recordings`` (the simulated bags, ``gpo.sim.record``), ``runs`` (the floor runs
of the papers' tables), ``datasets`` (downloaded real files, ``gpo.io.datasets``, unless ``$GPO_DATA_DIR`` names a
folder of copies).

A file's name ends in its ``key``: the first 16 hex digits of the sha256 of everything it is made from, written as
canonical JSON, and of the source files that make it, so that a changed input or a changed program makes a new
file instead of reading a stale one. ``write`` makes a file under a name of its own (``STEM-partial-TAG.SUFFIX``,
``gpo.io.partial``: its machine and process), seals it (the size and CRC-32 of each of its files beside it,
``NAME.crc32``: ``gpo.io.checksum``) and renames it into place, so processes sharing the folder never read one
another's half-written files. A reader asks ``intact`` before it reads: a file cut short or corrupted after it was
made (a crash mid-write on another machine sharing the folder, a full disk, a bad sector), or made without a seal, is
made again, never read as data. The check reads a file through once per process, then trusts it while its size and
modification time stay. A full disk is an error naming the cache folder; a caller that computed what it could not
keep goes on with it (``keep``: the message is logged).

A changed program leaves the files of the old one behind (a full set of recordings is about 6 GB), so the cache is
kept within ``MAX_BYTES``: after each ``write``, the oldest files of the kinds that can be made again
(``EVICTED_KINDS``; downloads stay) are deleted until it fits, the partial files of writes still at work counted. A
file still in use but old is made again when next wanted. The partial files of writes that were killed (``kill -9``)
are removed at each ``write`` (``clear_abandoned``).
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import logging
import os
import re
from collections.abc import Callable, Iterable
from pathlib import Path

import pooch

from gpo.io import checksum, partial
from gpo.io.outputs import FULL

_log = logging.getLogger(__name__)

ENVIRONMENT_VARIABLE = "GPO_CACHE_DIR"
KINDS = ("tables", "recordings", "runs", "datasets")
MAX_BYTES = 30 * 2**30  # beyond this the oldest files that can be made again go, 5 full sets of recordings
EVICTED_KINDS = ("tables", "recordings", "runs")
KEY_DIGITS = 12  # significant digits of a float in a key: far above any setting's precision, below rounding's
PARTIAL = re.compile(rf"-partial-{partial.TAG}")
"""What a partial file's name (or its seal's) holds: its writer's tag."""


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
    ``str``) and of the bytes of each file in ``sources``.

    Floats count to ``KEY_DIGITS`` significant digits: a value computed on another floating-point path (another
    BLAS kernel, another SIMD level) differs in its last bits, and names the same file."""
    digest = hashlib.sha256(json.dumps(_rounded(parts), sort_keys=True, default=str).encode())
    for source in sources:
        digest.update(Path(source).read_bytes())
    return digest.hexdigest()[:16]


def _rounded(value):
    """``value`` with every float rounded to ``KEY_DIGITS`` significant digits, in lists, tuples and dicts too."""
    if isinstance(value, float):
        return float(f"{value:.{KEY_DIGITS}g}")
    if isinstance(value, dict):
        return {name: _rounded(item) for name, item in value.items()}
    if isinstance(value, list | tuple):
        return [_rounded(item) for item in value]
    return value


def path(kind: str, name: str, file_key: str, suffix: str = "") -> Path:
    """The cache path ``<folder(kind)>/<name>-<file_key><suffix>``."""
    return folder(kind) / f"{name}-{file_key}{suffix}"


def intact(target: Path) -> bool:
    """Whether the cached file (or folder) ``target`` is there and matches the seal ``write`` put beside it. One that
    is not (cut short or corrupted since, or made without a seal) is to be made again with ``write``, never read."""
    return checksum.intact(target)


def write(target: Path, save: Callable[[Path], object]) -> Path:
    """Make ``target`` with ``save(partial)``, which writes a file (or a folder) at the path it is given: a name of
    this process's own beside ``target``, sealed and renamed to ``target`` once complete. When another process got
    there first and its file is intact, its file stays and this one's is removed (cached files of one name are
    identical); a file there that is not intact is replaced. A full disk is an OSError (errno ENOSPC) naming the cache
    folder, nothing left half written. Returns ``target``."""
    work = target.with_name(f"{target.stem}-partial-{partial.tag()}{target.suffix}")
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        clear_abandoned()
        partial.remove(work)
        save(work)
        if intact(target):
            partial.remove(work)
        else:
            checksum.seal(target, of=work)  # the seal first: a file in place is always sealed
            if work.is_dir():
                partial.remove(target)  # a folder is not renamed over another
            try:
                work.replace(target)
            except OSError:  # a folder: unless another process's landed there meanwhile, intact
                if not intact(target):
                    raise
                partial.remove(work)
    except OSError as error:
        partial.remove(work)
        if error.errno not in FULL:
            raise
        raise _full(target, "could not be kept") from None
    except BaseException:
        partial.remove(work)
        raise
    evict(keep=target)
    return target


def keep(target: Path, save: Callable[[Path], object]) -> bool:
    """``write``, for what the caller computed and can use without keeping it: on a full disk the message (naming the
    cache folder) is logged as a warning, nothing is kept, and False returned; else True."""
    try:
        write(target, save)
    except OSError as error:
        if error.errno not in FULL:
            raise
        _log.warning("%s", _full(target, "was not kept; what it holds is used as computed"))
        return False
    return True


def _full(target: Path, what: str) -> OSError:
    """The error of a cache file ``target`` the full disk stopped: the cache folder, the file, ``what`` became of it."""
    error = OSError(
        f"the cache folder {root()} is full (no space left on the device): {target.name} {what}; free "
        f"some room, or set {ENVIRONMENT_VARIABLE} to a folder with room"
    )
    error.errno = errno.ENOSPC
    return error


def clear_abandoned() -> list[Path]:
    """The partial files and folders (and seals) of the cache's writes whose writer is gone removed
    (``gpo.io.partial.abandoned``: a process that ended here, or another machine's unchanged for long); returns
    them."""
    cleared = []
    for kind in KINDS:
        for entry in folder(kind).glob("*-partial-*") if folder(kind).is_dir() else ():
            found = PARTIAL.search(entry.name)
            if found and partial.abandoned(found["host"], int(found["pid"]), entry):
                partial.remove(entry)
                cleared.append(entry)
    return cleared


def evict(keep: Path | None = None, max_bytes: int | None = None) -> list[Path]:
    """Delete the oldest (by modification time) files and folders of ``EVICTED_KINDS``, each with its seal, until the
    cache holds at most ``max_bytes`` (default ``MAX_BYTES``) in them, the partial files of writes at work counted;
    never ``keep``, nor a partial file. Returns what was deleted, oldest first."""
    limit = MAX_BYTES if max_bytes is None else max_bytes
    entries, at_work = [], 0
    for kind in EVICTED_KINDS:
        for entry in folder(kind).glob("*") if folder(kind).is_dir() else ():
            try:
                if PARTIAL.search(entry.name):
                    at_work += _size(entry)
                elif not entry.name.endswith(checksum.SUFFIX) and entry != keep:
                    entries.append((entry.stat().st_mtime, _size(entry), entry))
            except OSError:  # removed by another process meanwhile
                continue
    total = at_work + sum(size for _, size, _ in entries)
    total += _size(keep) if keep is not None and keep.exists() else 0
    deleted = []
    for _, size, entry in sorted(entries, key=lambda item: item[0]):
        if total <= limit:
            break
        with contextlib.suppress(OSError):  # another process removed it first
            partial.remove(entry)
            partial.remove(checksum.seal_path(entry))
        total -= size
        deleted.append(entry)
    return deleted


def _size(path: Path) -> int:
    """Bytes of the file, or of every file below the folder, ``path``."""
    if path.is_dir():
        return sum(item.stat().st_size for item in path.rglob("*") if item.is_file())
    return path.stat().st_size
