"""What a write leaves while it works, named after its writer, and whether the writer is gone.

A file (or a folder) is written under a name of its own first and renamed into place once whole: beside an output
(``gpo.io.outputs``: ``.NAME.TAG.partial/``) and in the cache (``gpo.io.cache``: ``STEM-partial-TAG.SUFFIX``, its
seal's ``NAME.crc32-partial-TAG``). ``TAG`` names the writer: this machine (``HOST``) and the process id. A write
killed before its rename (``kill -9``, the machine's power) leaves its partial behind; ``abandoned`` tells such a one
from the partial of a write still at work, here or on another machine sharing the folder, so that the next use of
the folder removes it (or, for an output's set, finishes it).
"""

from __future__ import annotations

import os
import re
import shutil
import socket
import time
from pathlib import Path

HOST = re.sub(r"\W", "_", socket.gethostname()) or "host"
"""This machine's name as a partial's name holds it: letters, digits and underscores."""
TAG = r"(?:(?P<host>\w+)-)?(?P<pid>\d+)"
"""The writer in a partial's name, as a regular expression: its machine and process id (the machine is missing from
the names of earlier versions)."""
STALE_S = 3600.0
"""A partial of another machine's process, unchanged for this long (seconds), was left by a write that stopped."""


def tag() -> str:
    """This process's tag: ``HOST-PID``."""
    return f"{HOST}-{os.getpid()}"


def abandoned(host: str | None, pid: int, path: Path, now: float | None = None) -> bool:
    """Whether the partial ``path`` of process ``pid`` on machine ``host`` was left by a write that will not finish:
    on this machine, its process is not running; on another (a folder shared by several), or an unnamed one (None),
    nothing of it changed for ``STALE_S`` seconds (``now``: the time to measure from, default now)."""
    if host == HOST:
        return not _running(pid)
    try:
        changed = max(
            [path.stat().st_mtime, *(p.stat().st_mtime for p in path.rglob("*"))]
            if path.is_dir()
            else [path.stat().st_mtime]
        )
    except OSError:  # removed meanwhile
        return False
    return (time.time() if now is None else now) - changed > STALE_S


def remove(path: Path) -> None:
    """Delete the file or folder ``path`` if it exists."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    elif path.exists() or path.is_symlink():
        path.unlink(missing_ok=True)


def _running(pid: int) -> bool:
    """Whether a process of id ``pid`` runs on this machine (one of another user counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    except (OverflowError, ValueError):  # no process has such an id
        return False
    return True
