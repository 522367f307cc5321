"""Writing results without losing anything.

Every command checks its output paths before it works (``check_output``: not a folder, not one of its inputs, a
folder that can be written, room on the disk where the size is known; ``check_output_folder``: a folder of results)
and never lets a result it flags as bad replace a file already there (``destination``: then it goes beside it).

The files of one result (a run's trajectory, its summary, the bag copy, a plot) replace the ones already there as
one set, or not at all (``write_together``; one file is a set of one, ``write_with``). Each is written in full under
its own name in a hidden folder beside its place, ``.NAME.TAG.partial/`` (``gpo.io.partial``: ``TAG`` names the
machine and the process); then, with Ctrl-C and SIGTERM held (``held_signals``), a journal of the set is written and
each file renamed into place. So a write that stops before the journal (a full disk, which the error names with the
file it stopped, Ctrl-C, an error) leaves the old set as it was and nothing half written, and a write killed during
the renames (``kill -9``) is finished the next time the folder is used (``clear_abandoned``, which ``check_output``,
``check_output_folder`` and every write run first; they also remove what writes killed before their journal left). A
rename that fails, the one step that cannot be readied beforehand, puts back the files already renamed: the old set
stays whole, and the new one is written beside it, each name with ``.new`` after its first part (``beside_path``).
"""

from __future__ import annotations

import errno
import json
import os
import re
import shutil
import signal
import threading
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

from gpo.io import partial

STAGING = re.compile(rf"^\.(?P<name>.+)\.{partial.TAG}\.partial$")
"""The hidden folder a file is written in before it is renamed into place: ``.NAME.TAG.partial``."""
JOURNAL, FIRST, OLD, TEMPORARY = ".set", ".first", ".old", ".tmp"
"""What a staging folder holds beside the new file NAME: the set's journal (in the first file's folder; written
through its name and ``TEMPORARY``), the path of the first file's folder (in the others'), the file it replaces (a
hard link or a copy, to put it back)."""


def check_output(path, inputs: Iterable = (), option: str = "--out", needed_bytes: int = 0) -> Path:
    """``path`` checked to be writable as a new or replaced file; ValueError otherwise.

    Refused: a folder; one of ``inputs`` (the same resolved path, or the same file under another name, a hard or
    symbolic link); a place whose nearest existing folder cannot be written or is not a folder; less free room
    there than ``needed_bytes``. ``option`` names the command-line option in the messages. What killed writes left
    in its folder is dealt with first (``clear_abandoned``).
    """
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{option} {path} is a folder; expected a file name")
    if path.parent.is_dir():
        clear_abandoned(path.parent)
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
    ``option`` names the command-line option in the messages. What killed writes left in it is dealt with
    (``clear_abandoned``)."""
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
    if path.is_dir():
        clear_abandoned(path)
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


FULL = (errno.ENOSPC, errno.EDQUOT)
"""What a write fails with when the disk, or the user's share of it, is full."""


def _full(path: Path, targets: list[Path]) -> OSError:
    """The error of a write of ``path`` (one of ``targets``, a set) that found the disk full: it names ``path`` and
    what was kept."""
    if not any(target.exists() for target in targets):
        kept = "nothing is left half written"
    elif len(targets) == 1:
        kept = "the file already there is kept as it was"
    else:
        kept = "the files already there are kept as they were"
    error = OSError(f"{path}: the disk is full (no space left on the device); {kept}: free some room, then run again")
    error.errno = errno.ENOSPC
    return error


def write_together(writers: dict[Path, Callable[[Path], object]]) -> list[Path]:
    """Each ``writers[path](temporary)`` writes a file (or a bag's folder) at ``temporary``, a path of ``path``'s own
    name in a hidden folder beside it; once every one is whole they are renamed onto their paths as one set (see the
    module), the folders above made as needed. Returns the paths. A full disk is an OSError (errno ENOSPC) naming the
    file it stopped, not its temporary name; a rename that fails, an OSError saying where the new set went
    (``beside_path``)."""
    targets = [Path(path) for path in writers]
    if not targets:
        return []
    for folder in dict.fromkeys(target.parent for target in targets):
        if folder.is_dir():
            clear_abandoned(folder)
    folders, staged, current = [], {}, targets[0]
    try:
        for current, write in zip(targets, writers.values(), strict=True):
            folder = current.with_name(f".{current.name}.{partial.tag()}.partial")
            current.parent.mkdir(parents=True, exist_ok=True)
            folder.mkdir()
            folders.append(folder)
            if len(folders) > 1:  # the first file's folder holds the set's journal
                (folder / (current.name + FIRST)).write_text(str(folders[0]))
            write(folder / current.name)
            staged[current] = folder / current.name
        _commit(staged)
    except OSError as error:
        if error.errno not in FULL:
            raise
        raise _full(current, targets) from None
    finally:
        for folder in folders:
            partial.remove(folder)
    return targets


def _commit(staged: dict[Path, Path]) -> None:
    """Rename each staged file onto its target, Ctrl-C and SIGTERM held: for a set, its journal first, and each file
    replaced but the last kept beside its new one (``OLD``) to be put back should a later rename fail."""
    targets = list(staged)
    with held_signals():
        if len(staged) > 1:
            _write_journal(staged)
        done = []
        try:
            for target, new in staged.items():
                old = _kept(target, new) if target != targets[-1] else None
                os.replace(new, target)
                done.append((target, old))
        except OSError as error:
            raise _put_back(staged, done, error) from None


def _kept(target: Path, new: Path) -> Path | None:
    """The file at ``target`` kept beside ``new`` (a hard link, or a copy where the file system has none), or None
    when there is none."""
    if not target.is_file():
        return None
    old = new.with_name(new.name + OLD)
    try:
        os.link(target, old)
    except OSError:
        shutil.copy2(target, old)
    return old


def _put_back(staged: dict[Path, Path], done: list[tuple[Path, Path | None]], error: OSError) -> OSError:
    """The set not replaced: its journal removed, the files renamed so far put back, every new file beside its old
    (``beside_path``); the error that says so."""
    _journal_path(staged).unlink(missing_ok=True)
    for target, old in done:
        os.replace(target, beside_path(target))
        if old is not None:
            os.replace(old, target)
    for target, new in staged.items():
        if new.exists():
            os.replace(new, beside_path(target))
    paths = ", ".join(map(str, staged))
    besides = ", ".join(str(beside_path(target)) for target in staged)
    failure = OSError(
        f"{paths} could not be replaced ({error.strerror or error}): the files already there are kept "
        f"as they were, and this result is written beside them: {besides}"
    )
    failure.errno = error.errno
    return failure


def beside_path(path) -> Path:
    """Where a file of a set that could not replace ``path`` goes: ``.new`` after the first part of its name
    (``t.tum``: ``t.new.tum``; its summary ``t.summary.yaml``: ``t.new.summary.yaml``), so that the set still pairs."""
    path = Path(path)
    head, dot, rest = path.name.partition(".")
    return path.with_name(f"{head}.new{dot}{rest}")


def _journal_path(staged: dict[Path, Path]) -> Path:
    """Where a set's journal is: in the first file's staging folder, the file's name and ``JOURNAL``."""
    target, new = next(iter(staged.items()))
    return new.with_name(target.name + JOURNAL)


def _write_journal(staged: dict[Path, Path]) -> None:
    """The set's journal: each new file and its target, through a temporary name."""
    journal = _journal_path(staged)
    temporary = journal.with_name(journal.name + TEMPORARY)
    temporary.write_text(json.dumps([[str(new), str(target)] for target, new in staged.items()]))
    os.replace(temporary, journal)


def clear_abandoned(folder) -> list[Path]:
    """The hidden folders of writes into ``folder`` whose writer is gone (``gpo.io.partial.abandoned``) dealt with: a
    set whose journal was written is finished (each file still waiting renamed into place), anything else removed.
    Returns those folders."""
    cleared = []
    for entry in sorted(Path(folder).glob(".*.partial")):
        found = STAGING.match(entry.name)
        if found and _staging(entry, found["name"]) and partial.abandoned(found["host"], int(found["pid"]), entry):
            _finish(entry, found["name"])
            cleared.append(entry)
    return cleared


def _staging(folder: Path, name: str) -> bool:
    """Whether ``folder`` is a staging folder of the file ``name``: a folder holding nothing but what a write puts
    there (a folder the user named alike is left alone)."""
    ours = {name, *(name + extra for extra in (JOURNAL, JOURNAL + TEMPORARY, FIRST, OLD))}
    try:
        return folder.is_dir() and all(child.name in ours for child in folder.iterdir())
    except OSError:  # removed meanwhile
        return False


def _finish(folder: Path, name: str) -> None:
    """The staging ``folder`` of the file ``name`` of a write whose writer is gone: its set finished when its journal
    was written (from the first file's folder, which another file's names), then removed."""
    first = folder / (name + FIRST)
    if first.is_file():
        first_folder = Path(first.read_text())
        found = STAGING.match(first_folder.name)
        if found and first_folder.is_dir():
            _finish(first_folder, found["name"])
    for new, target in _journal(folder / (name + JOURNAL)):
        if new.exists():
            os.replace(new, target)
    for new, _ in _journal(folder / (name + JOURNAL)):
        partial.remove(new.parent)
    partial.remove(folder)


def _journal(path: Path) -> list[tuple[Path, Path]]:
    """The (new file, target) pairs of the journal ``path``: none when there is none, or it cannot be read, or it
    names a file outside a staging folder beside its own target."""
    try:
        pairs = [(Path(new), Path(target)) for new, target in json.loads(path.read_text())]
    except (OSError, ValueError, TypeError):
        return []
    sound = all(
        STAGING.match(new.parent.name) and new.parent.parent == target.parent and new.name == target.name
        for new, target in pairs
    )
    return pairs if sound else []


@contextmanager
def held_signals() -> Iterator[None]:
    """Ctrl-C and SIGTERM held while the block runs, then met by the handlers they would have met, in the order they
    came (a handler set from Python's side; in the main thread, where signals are handled)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held = []
    kinds = [s for s in (signal.SIGINT, signal.SIGTERM) if signal.getsignal(s) is not None]
    previous = {s: signal.signal(s, lambda signum, frame: held.append(signum)) for s in kinds}
    try:
        yield
    finally:
        for kind, handler in previous.items():
            signal.signal(kind, handler)
        for signum in held:
            handler = previous[signum]
            if callable(handler):
                handler(signum, None)
            elif handler == signal.SIG_DFL:
                signal.raise_signal(signum)


def write_with(path, write: Callable[[Path], object]) -> Path:
    """``write(temporary)`` then the rename onto ``path`` (``write_together``, a set of one); return ``path``."""
    return write_together({Path(path): write})[0]


def write_text(path, text: str) -> Path:
    """``text`` written to ``path`` through a temporary name; return ``path``."""
    return write_with(path, lambda temporary: temporary.write_text(text))


def write_json(path, document) -> Path:
    """``document`` as indented JSON text (``write_text``), its folder made when missing; return ``path``."""
    return write_text(path, json.dumps(document, indent=1) + "\n")
