"""Writing results without losing anything.

Every command checks its output paths before it works (``check_output``: not a folder, not one of its inputs, a
folder that can be written, room on the disk where the size is known; ``check_output_folder``: a folder of results),
writes each file to a temporary name beside it and renames it into place (``replacing``), so that an interrupted
write leaves the old file whole and a full disk is named with the file it stopped, and never lets a result it flags
as bad replace a file already there (``destination``: then it goes beside it).
"""

from __future__ import annotations

import errno
import json
import os
import shutil
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path


def check_output(path, inputs: Iterable = (), option: str = "--out", needed_bytes: int = 0) -> Path:
    """``path`` checked to be writable as a new or replaced file; ValueError otherwise.

    Refused: a folder; one of ``inputs`` (the same resolved path, or the same file under another name, a hard or
    symbolic link); a place whose nearest existing folder cannot be written or is not a folder; less free room
    there than ``needed_bytes``. ``option`` names the command-line option in the messages.
    """
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{option} {path} is a folder; expected a file name")
    for source in inputs:
        if source is not None and _same(path, Path(source)):
            raise ValueError(f"{option} {path} is an input of this command ({source}); it would be overwritten")
    folder = _existing_folder(path)
    if not folder.is_dir():
        raise ValueError(f"{option} {path}: {folder} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ValueError(f"{option} {path}: the folder {folder} cannot be written (read-only)")
    if path.exists() and not os.access(path, os.W_OK):
        raise ValueError(f"{option} {path} exists and cannot be written (read-only)")
    free = shutil.disk_usage(folder).free
    if needed_bytes and free < needed_bytes:
        raise ValueError(f"{option} {path}: {free / 1e6:.1f} MB free in {folder}, {needed_bytes / 1e6:.1f} MB needed")
    return path


def check_output_folder(path, inputs: Iterable = (), option: str = "--out") -> Path:
    """``path`` checked to be a folder results can be written into (made when missing); ValueError otherwise.

    Refused: one of ``inputs``; a file; a place whose nearest existing folder cannot be written or is not a folder.
    ``option`` names the command-line option in the messages."""
    path = Path(path)
    for source in inputs:
        if source is not None and _same(path, Path(source)):
            raise ValueError(f"{option} {path} is an input of this command ({source}); name a folder for the results")
    if path.exists() and not path.is_dir():
        raise ValueError(f"{option} {path} is a file; expected a folder for the results (made when missing)")
    folder = path if path.is_dir() else _existing_folder(path)
    if not folder.is_dir():
        raise ValueError(f"{option} {path}: {folder} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ValueError(f"{option} {path}: the folder {folder} cannot be written (read-only)")
    return path


def _same(path: Path, source: Path) -> bool:
    if path.resolve() == source.resolve():
        return True
    try:
        return path.exists() and source.exists() and path.samefile(source)
    except OSError:
        return False


def _existing_folder(path: Path) -> Path:
    """The nearest folder above ``path`` that exists (where ``path``'s missing folders would be made)."""
    folder = path.absolute().parent
    while not folder.exists():
        folder = folder.parent
    return folder


def flagged_path(path) -> Path:
    """Where a flagged result of ``path`` goes when ``path`` exists: ``name.flagged.ext`` beside it."""
    path = Path(path)
    return path.with_name(f"{path.stem}.flagged{path.suffix}")


def destination(path, flagged: bool, force: bool = False) -> Path:
    """Where to write a result meant for ``path``: ``path`` itself unless the result is ``flagged`` as bad and
    ``path`` already holds a file (a good one, perhaps) and not ``force``; then ``flagged_path(path)``."""
    path = Path(path)
    return flagged_path(path) if flagged and path.exists() and not force else path


@contextmanager
def replacing(path) -> Iterator[Path]:
    """A temporary path for ``path``: its own name (writers that go by the suffix, or name a bag folder's files
    after it, still do) in a hidden folder beside it, renamed onto ``path`` when the block ends without error;
    the hidden folder is removed either way. The folders above are made as needed. A full disk is an OSError
    (errno ENOSPC) that names ``path``, not the temporary one."""
    path = Path(path)
    folder = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        folder.mkdir()
        try:
            yield folder / path.name
            os.replace(folder / path.name, path)
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    except OSError as error:
        if error.errno not in FULL:
            raise
        raise _full(path) from None


FULL = (errno.ENOSPC, errno.EDQUOT)
"""What a write fails with when the disk, or the user's share of it, is full."""


def _full(path: Path) -> OSError:
    """The error of a write of ``path`` that found the disk full: it names ``path`` and what was kept."""
    kept = "the file already there is kept as it was" if path.exists() else "nothing is left half written"
    error = OSError(f"{path}: the disk is full (no space left on the device); {kept}: free some room, then run again")
    error.errno = errno.ENOSPC
    return error


def write_with(path, write: Callable[[Path], object]) -> Path:
    """``write(temporary)`` then the rename onto ``path`` (``replacing``); return ``path``."""
    with replacing(path) as temporary:
        write(temporary)
    return Path(path)


def write_text(path, text: str) -> Path:
    """``text`` written to ``path`` through a temporary name; return ``path``."""
    return write_with(path, lambda temporary: temporary.write_text(text))


def write_json(path, document) -> Path:
    """``document`` as indented JSON text (``write_text``), its folder made when missing; return ``path``."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    return write_text(path, json.dumps(document, indent=1) + "\n")
