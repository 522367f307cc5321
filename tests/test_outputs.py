"""gpo.io.outputs' writers: what they write reads back, into a folder made for it, with nothing else left behind; the
files of one result replace the old ones as one, whatever stops the write (a full disk, Ctrl-C, kill -9)."""

import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gpo.io import partial
from gpo.io.outputs import STAGING, check_output, clear_abandoned, write_json, write_text, write_together


def test_write_json_makes_the_folder_and_reads_back(tmp_path):
    target = tmp_path / "results" / "run.json"
    document = {"runs": [{"preset": "long1", "final_error_percent": 0.035}], "summary": {"met": True}}
    assert write_json(target, document) == target
    assert json.loads(target.read_text()) == document
    assert target.read_text().endswith("}\n")
    assert [path.name for path in (tmp_path / "results").iterdir()] == ["run.json"]


def test_write_text_replaces_a_file_whole(tmp_path):
    target = tmp_path / "note.txt"
    write_text(target, "a longer first text\n")
    write_text(target, "short\n")
    assert target.read_text() == "short\n"
    assert sorted(path.name for path in tmp_path.iterdir()) == ["note.txt"]


def _old_set(folder: Path) -> dict[Path, str]:
    """Two files of an earlier result, each saying what it is."""
    files = {folder / "t.tum": "old trajectory\n", folder / "t.summary.yaml": "old summary\n"}
    for path, text in files.items():
        path.write_text(text)
    return files


def _new_set(folder: Path, failing: BaseException | None = None) -> dict[Path, object]:
    """The writers of a new result of the same two files; the second raises ``failing`` once half written."""

    def second(temporary: Path) -> None:
        temporary.write_text("new sum")
        if failing is not None:
            raise failing
        temporary.write_text("new summary\n")

    return {
        folder / "t.tum": lambda temporary: temporary.write_text("new trajectory\n"),
        folder / "t.summary.yaml": second,
    }


def _contents(folder: Path) -> dict[str, str]:
    """Every entry of ``folder`` by name, a file's text (a hidden partial folder shows as its name)."""
    return {path.name: path.read_text() if path.is_file() else "<folder>" for path in sorted(folder.iterdir())}


def test_a_set_of_files_replaces_the_old_set_as_one(tmp_path):
    _old_set(tmp_path)
    assert write_together(_new_set(tmp_path)) == [tmp_path / "t.tum", tmp_path / "t.summary.yaml"]
    assert _contents(tmp_path) == {"t.summary.yaml": "new summary\n", "t.tum": "new trajectory\n"}


@pytest.mark.parametrize(
    ("failing", "raised", "words"),
    [
        (OSError(errno.ENOSPC, "No space left on device"), OSError, "t.summary.yaml: the disk is full"),
        (KeyboardInterrupt(), KeyboardInterrupt, None),
    ],
)
def test_a_set_that_fails_before_its_renames_leaves_the_old_set_whole(tmp_path, failing, raised, words):
    before = {path.name: text for path, text in _old_set(tmp_path).items()}
    with pytest.raises(raised, match=words):
        write_together(_new_set(tmp_path, failing))
    assert _contents(tmp_path) == before


KILLED_WRITER = """
import os, signal, sys
from pathlib import Path
import gpo.io.outputs as outputs
folder, stop = Path(sys.argv[1]), sys.argv[2]
rename = os.replace

def replace(source, target):
    if Path(target).name == stop:  # killed at once, as kill -9 does, before this rename
        os.kill(os.getpid(), signal.SIGKILL)
    rename(source, target)

def written(text, name):
    def write(temporary):
        if name == stop:
            temporary.write_text(text[:3])
            os.kill(os.getpid(), signal.SIGKILL)
        temporary.write_text(text)
    return write

outputs.os.replace = replace
outputs.write_together({folder / "t.tum": written("new trajectory\\n", "t.tum*"),
                        folder / "t.summary.yaml": written("new summary\\n", "t.summary.yaml*")})
"""


@pytest.mark.parametrize(
    ("stop", "after"),
    [
        ("t.summary.yaml*", "old"),  # killed while the second file is written: the old set stays
        ("t.tum", "new"),  # killed after the journal, before the first rename: the set is finished
        ("t.summary.yaml", "new"),
    ],  # killed between the two renames: the set is finished
)
def test_a_set_whose_writer_was_killed_is_whole_the_next_time_its_folder_is_used(tmp_path, stop, after):
    _old_set(tmp_path)
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[1])}
    killed = subprocess.run([sys.executable, "-c", KILLED_WRITER, str(tmp_path), stop], env=env, check=False)
    assert killed.returncode == -signal.SIGKILL
    assert any(path.name.endswith(".partial") for path in tmp_path.iterdir())  # what the killed write left
    check_output(tmp_path / "other.tum")  # the folder used again
    expected = {"t.tum": f"{after} trajectory\n", "t.summary.yaml": f"{after} summary\n"}
    assert _contents(tmp_path) == expected


def test_a_partial_folder_of_a_writer_still_at_work_is_left_alone(tmp_path):
    """This process's, and another machine's (or an earlier version's, which named no machine) unless unchanged for
    an hour; a folder that only looks like one (it holds what no write puts there) is the user's."""
    host, pid = partial.HOST, os.getpid()
    own, elsewhere, stale = (
        tmp_path / f".{name}.{host}{other}-{pid}.partial"
        for name, other in (("t.tum", ""), ("u.tum", "x"), ("v.tum", "x"))
    )
    earlier, earlier_stale, users = (tmp_path / f".{name}.{pid}.partial" for name in ("w.tum", "x.tum", "photos"))
    for folder in (own, elsewhere, stale, earlier, earlier_stale, users):
        folder.mkdir()
        name = "holiday.jpg" if folder == users else STAGING.match(folder.name)["name"]
        (folder / name).write_text("half")
    old = time.time() - partial.STALE_S - 60
    for folder in (stale, earlier_stale, users):
        for path in (*folder.iterdir(), folder):
            os.utime(path, (old, old))
    assert clear_abandoned(tmp_path) == [stale, earlier_stale]
    assert sorted(path.name for path in tmp_path.iterdir()) == sorted(
        path.name for path in (own, elsewhere, earlier, users)
    )


def test_a_rename_that_fails_puts_the_old_set_back_and_the_new_one_beside_it(tmp_path, monkeypatch):
    _old_set(tmp_path)
    rename = os.replace

    def replace(source, target):
        if Path(target) == tmp_path / "t.summary.yaml" and Path(source).parent.name.endswith(".partial"):
            raise PermissionError(errno.EACCES, "Permission denied", str(target))
        rename(source, target)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(
        OSError,
        match=r"t\.tum, .*t\.summary\.yaml could not be replaced.*kept as they were.*"
        r"beside them: .*t\.new\.tum, .*t\.new\.summary\.yaml",
    ):
        write_together(_new_set(tmp_path))
    assert _contents(tmp_path) == {
        "t.new.summary.yaml": "new summary\n",
        "t.new.tum": "new trajectory\n",
        "t.summary.yaml": "old summary\n",
        "t.tum": "old trajectory\n",
    }


def test_ctrl_c_during_the_renames_waits_for_the_whole_set(tmp_path, monkeypatch):
    """The signal comes as the first file is renamed into place: the second follows, then the signal is met."""
    _old_set(tmp_path)
    rename = os.replace

    def replace(source, target):
        if Path(target) == tmp_path / "t.tum":
            os.kill(os.getpid(), signal.SIGINT)
        rename(source, target)

    monkeypatch.setattr(os, "replace", replace)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)  # Ctrl-C as in a terminal, whatever the runner's
    try:
        with pytest.raises(KeyboardInterrupt):
            write_together(_new_set(tmp_path))
    finally:
        signal.signal(signal.SIGINT, before)
    assert _contents(tmp_path) == {"t.summary.yaml": "new summary\n", "t.tum": "new trajectory\n"}
