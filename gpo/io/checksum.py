"""A seal on a file or a folder of files: each file's size and CRC-32 kept beside it, so that one cut short or
corrupted after it was made (a crash mid-write on another machine sharing the folder, a full disk, a bad sector, a
bad copy) is found out when it is next read, not read as data.

``seal(path)`` writes ``PATH.crc32`` beside ``path``: a line ``CRC SIZE NAME`` for the file, or for each file of the
folder in name order (its name within the folder), through a temporary name. ``intact(path)`` says whether ``path``
is there and matches its seal: the same files, each of its size and CRC-32. A file is read through once per process
while its size, modification time and inode stay the same, then taken as checked. CRC-32 finds every error burst up to
32 bits and misses another kind of damage once in 4e9, and it costs less than sha256: the sample recording (300 MB,
from the page cache) is checked in 0.24 s where sha256 took 0.39 s and the odometry over it takes 2.9 s. It guards
against accidents, not against someone forging a file (a content's identity, such as a sweep's key, is its sha256).
"""

from __future__ import annotations

import zlib
from pathlib import Path

from gpo.io import partial

SUFFIX = ".crc32"
"""What a seal's name adds to the name of what it seals."""
CHUNK_BYTES = 2**22

_CHECKED: dict[Path, tuple] = {}  # path -> (what os.stat said of its files, its seal's text) when they last matched


def sums(path) -> dict[str, tuple[int, int]]:
    """(CRC-32, size in bytes) of the file ``path`` (by its name), or of each file of the folder ``path`` (by its
    name within it). Raises OSError when it cannot be read."""
    path = Path(path)
    files = _files(path)
    if not files:
        raise FileNotFoundError(f"{path}: no such file or folder of files")
    found, buffer = {}, bytearray(CHUNK_BYTES)
    view = memoryview(buffer)
    for file in files:
        crc, size = 0, 0
        with file.open("rb", buffering=0) as stream:
            while read := stream.readinto(buffer):
                crc, size = zlib.crc32(view[:read], crc), size + read
        found[str(file.relative_to(path)) if path.is_dir() else path.name] = (crc, size)
    return found


def seal_path(path) -> Path:
    """Where the seal of ``path`` is: beside it, its name with ``SUFFIX``."""
    path = Path(path)
    return path.with_name(path.name + SUFFIX)


def seal(path, of=None) -> Path:
    """Write the seal of ``path``: the ``sums`` of ``of`` (default ``path``; e.g. the temporary name it is made under,
    its file named as ``path``'s), through a name of this process's own renamed into place. Returns the seal's
    path."""
    path = Path(path)
    found = sums(path if of is None else of)
    if of is not None and not Path(of).is_dir():
        found = {path.name: found[Path(of).name]}
    target = seal_path(path)
    work = target.with_name(f"{target.name}-partial-{partial.tag()}")
    try:
        work.write_text("".join(f"{crc:08x} {size} {name}\n" for name, (crc, size) in found.items()))
        work.replace(target)
    except BaseException:
        work.unlink(missing_ok=True)
        raise
    return target


def sealed(path) -> dict[str, tuple[int, int]] | None:
    """The (CRC-32, size) by file name that the seal of ``path`` holds, or None when it has none or one that cannot
    be read."""
    try:
        lines = seal_path(path).read_text(encoding="utf-8").splitlines()
        found = {}
        for line in lines:
            crc, size, name = line.split(" ", 2)
            found[name] = (int(crc, 16), int(size))
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    return found or None


def intact(path) -> bool:
    """Whether ``path`` (a file or a folder) exists, has a seal, and matches it: the same files, each of its size and
    CRC-32; read through the first time in this process, then checked by what ``os.stat`` says while that stays."""
    path = Path(path)
    expected = sealed(path)
    if expected is None:
        return False
    try:
        signature = _signature(path)
        if {name: size for name, (_, size) in expected.items()} != {name: size for name, size, _ in signature}:
            return False  # files missing, added or cut short: no need to read them
        if _CHECKED.get(path) == (signature, expected):
            return True
        matches = sums(path) == expected
    except OSError:  # removed meanwhile
        return False
    if matches:
        _CHECKED[path] = (signature, expected)
    return matches


def _files(path: Path) -> list[Path]:
    if path.is_dir():
        return sorted(p for p in path.rglob("*") if p.is_file())
    return [path] if path.is_file() else []


def _signature(path: Path) -> tuple:
    """(name, size, (inode, modification time)) of the file, or of every file of the folder: what a change to any
    of them changes."""
    return tuple(
        (
            str(file.relative_to(path)) if path.is_dir() else path.name,
            status.st_size,
            (status.st_ino, status.st_mtime_ns),
        )
        for file in _files(path)
        for status in (file.stat(),)
    )
