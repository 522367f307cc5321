"""The one cache: one environment variable, one folder per kind, one key scheme, files sealed and renamed into place;
a recording, table or floor run damaged after it was made (cut short, a bit turned) is made again, never read."""

import dataclasses
import errno
import hashlib
import io
import json
import logging
import os
import subprocess
import sys
import time
import zlib
from pathlib import Path

import numpy as np
import pooch
import pytest

import gpo.experiments.runs as experiment_runs
from gpo.experiments.runs import floor_run, route_config
from gpo.floor_image.analytic import analytic_table
from gpo.floor_image.image import FloorImage
from gpo.io import cache, checksum, datasets, partial
from gpo.io.fingerprint import sources as module_sources
from gpo.sim import record
from gpo.sim.plans import MotionPlan
from gpo.sim.record import PRESETS, Setup, recording
from gpo.sim.rigs import t265_rig


def test_the_folder_is_the_environment_variables_else_the_users_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("GPO_CACHE_DIR", str(tmp_path))
    assert cache.root() == tmp_path
    assert [cache.folder(kind) for kind in cache.KINDS] == [tmp_path / kind for kind in cache.KINDS]
    monkeypatch.delenv("GPO_CACHE_DIR")
    assert cache.root() == Path(pooch.os_cache("gpo"))
    with pytest.raises(ValueError, match="unknown cache kind 'table'; the kinds are tables, recordings"):
        cache.folder("table")


def test_the_key_is_the_sha256_of_the_canonical_json_and_the_sources():
    parts = ({"b": 1, "a": [0.5, "x"]}, "ros1")
    expected = hashlib.sha256(json.dumps(parts, sort_keys=True).encode()).hexdigest()[:16]
    assert cache.key(*parts) == expected
    assert cache.key({"a": [0.5, "x"], "b": 1}, "ros1") == expected  # the order of a dict's keys does not matter
    assert cache.key({"b": 1, "a": [0.5, "x"]}, "ros2") != expected
    sources = module_sources("gpo.sim.record")
    digest = hashlib.sha256(json.dumps(parts, sort_keys=True).encode())
    for source in sources:
        digest.update(source.read_bytes())
    assert cache.key(*parts, sources=sources) == digest.hexdigest()[:16]


def test_floats_differing_in_their_last_bits_name_the_same_file():
    # a plan's peak heading as OpenBLAS's SkylakeX and Nehalem kernels compute it
    value, other_path = 0.4348502184339108, 0.4348502184339107
    assert cache.key({"peak_heading_rad": value}) == cache.key({"peak_heading_rad": other_path})
    assert cache.key({"peak_heading_rad": value}) != cache.key({"peak_heading_rad": value * (1 + 1e-9)})
    assert cache.key([1.0, (2.5, {"x": 3.25})]) == cache.key([1.0, [2.5, {"x": 3.25}]])


def test_a_changed_source_changes_the_key(tmp_path):
    source = tmp_path / "module.py"
    source.write_text("A = 1\n")
    before = cache.key("x", sources=[source])
    source.write_text("A = 2\n")
    assert cache.key("x", sources=[source]) != before


def test_write_renames_a_complete_file_into_place_and_keeps_the_first(tmp_path):
    target = cache.path("runs", "run", "0123456789abcdef", ".npz").relative_to(cache.root())
    target = tmp_path / target
    seen = []

    def save(partial: Path) -> None:
        seen.append(partial)
        assert partial.parent == target.parent and partial != target and partial.suffix == ".npz"
        np.savez(partial, value=np.arange(3))

    assert cache.write(target, save) == target
    sealed = [target.name, f"{target.name}.crc32"]  # the file and its seal
    assert sorted(path.name for path in target.parent.iterdir()) == sealed
    cache.write(target, lambda partial: np.savez(partial, value=np.arange(5)))  # another process, second
    assert np.load(target)["value"].tolist() == [0, 1, 2]
    assert sorted(path.name for path in target.parent.iterdir()) == sealed


def test_a_failed_write_leaves_nothing(tmp_path):
    target = tmp_path / "runs" / "run-0123.npz"

    def fail(partial: Path) -> None:
        partial.write_text("half")
        raise OSError("disk full")

    with pytest.raises(OSError, match="disk full"):
        cache.write(target, fail)
    assert list(target.parent.iterdir()) == []


def _ended_process() -> int:
    """The id of a process that ran here and has ended."""
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def test_what_killed_writes_left_goes_the_next_time_the_cache_is_written(tmp_path, monkeypatch):
    """A write killed before its rename (kill -9) leaves its partial file or folder, and its seal's; the next write
    into the cache removes those of a process that ended here, of another machine's left unchanged for an hour, and of
    the earlier form of the name (the process alone); it leaves those of writes that may still be at work."""
    monkeypatch.setenv("GPO_CACHE_DIR", str(tmp_path))
    ended, host, old = _ended_process(), partial.HOST, time.time() - partial.STALE_S - 60
    left = {
        "recordings": [
            f"bag-0123-partial-{host}-{ended}.bag",
            f"ros2-0123-partial-{host}-{ended}",
            f"bag-0123.bag.crc32-partial-{host}-{ended}",
            f"bag-4567-partial-{ended}.bag",
        ],
        "tables": [f"table-0123-partial-elsewhere-{ended}.npz"],
    }
    kept = {"recordings": [f"bag-89ab-partial-{host}-{os.getpid()}.bag", f"bag-cdef-partial-elsewhere-{ended}.bag"]}
    for kind, names in [*left.items(), *kept.items()]:
        for name in names:
            path = cache.folder(kind) / name
            path.parent.mkdir(parents=True, exist_ok=True)
            if name.startswith("ros2"):
                path.mkdir()
                (path / "data.db3").write_bytes(b"x" * 100)
            else:
                path.write_bytes(b"x" * 100)
    for name in (f"table-0123-partial-elsewhere-{ended}.npz",):
        os.utime(cache.folder("tables") / name, (old, old))
    os.utime(cache.folder("recordings") / f"bag-4567-partial-{ended}.bag", (old, old))
    cache.write(cache.path("runs", "run", "0123456789abcdef", ".npz"), lambda p: np.savez(p, value=np.arange(3)))
    assert sorted(p.name for p in cache.folder("recordings").iterdir()) == sorted(kept["recordings"])
    assert list(cache.folder("tables").iterdir()) == []


def test_a_partial_file_still_written_counts_toward_the_cache_s_size(tmp_path, monkeypatch):
    monkeypatch.setenv("GPO_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(cache, "MAX_BYTES", 2500)
    older = cache.path("recordings", "older", "0123456789abcdef", ".bin")
    older.parent.mkdir(parents=True)
    older.write_bytes(b"x" * 1000)
    os.utime(older, (1e9, 1e9))
    at_work = cache.folder("recordings") / f"bag-89ab-partial-{partial.HOST}-{os.getpid()}.bag"
    at_work.write_bytes(b"x" * 1000)  # a render still at work, here
    new = cache.write(cache.path("recordings", "new", "fedcba9876543210", ".bin"), lambda p: p.write_bytes(b"y" * 1000))
    assert not older.exists() and at_work.exists() and new.exists()  # 3000 bytes with the partial: the oldest goes


def test_a_full_cache_is_named_and_what_was_computed_is_still_used(tmp_path, monkeypatch, caplog):
    """A remap table built while the cache's disk is full is used, not kept; the message names the cache folder. A
    file that cannot be had without keeping it (a recording) is an error naming the folder."""
    monkeypatch.setenv("GPO_CACHE_DIR", str(tmp_path))

    def full(path, **arrays):
        Path(path).write_bytes(b"half")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(np, "savez", full)
    rig = t265_rig()
    floor = FloorImage.top_view(metres_per_pixel=4e-3)
    with caplog.at_level(logging.WARNING, logger="gpo.io.cache"):
        table = analytic_table(rig.camera, rig.mount, floor)
    built = analytic_table(rig.camera, rig.mount, floor, cache=False)
    np.testing.assert_array_equal(table.map_x, built.map_x)
    assert (
        f"the cache folder {tmp_path} is full" in caplog.text and f"table-{table.key}.npz was not kept" in caplog.text
    )
    assert list(cache.folder("tables").iterdir()) == []
    with pytest.raises(OSError, match=rf"the cache folder {tmp_path} is full .*bag-0123\.bag could not be kept"):
        cache.write(cache.path("recordings", "bag", "0123", ".bag"), lambda p: full(p))
    assert list(cache.folder("recordings").iterdir()) == []


def test_tables_and_downloads_live_under_the_one_variable(tmp_path, monkeypatch):
    monkeypatch.setenv("GPO_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("GPO_DATA_DIR", raising=False)
    rig = t265_rig()
    table = analytic_table(rig.camera, rig.mount, FloorImage.top_view(metres_per_pixel=4e-3))
    assert sorted(path.name for path in (tmp_path / "tables").iterdir()) == [
        f"table-{table.key}.npz",
        f"table-{table.key}.npz.crc32",
    ]
    assert datasets.data_dir() == tmp_path / "datasets"
    monkeypatch.setenv("GPO_DATA_DIR", str(tmp_path / "copies"))  # the real-data folder stays a folder of its own
    assert datasets.data_dir() == tmp_path / "copies"


def test_the_oldest_files_that_can_be_made_again_go_when_the_cache_is_full(tmp_path, monkeypatch):
    monkeypatch.setenv("GPO_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(cache, "MAX_BYTES", 3500)
    made = {}
    for age, (kind, name) in enumerate(
        [
            ("recordings", "old"),
            ("datasets", "download"),
            ("tables", "older-code"),
            ("recordings", "bag2"),
            ("runs", "run"),
        ]
    ):
        path = cache.path(kind, name, "0123456789abcdef", ".bin")
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(b"x" * 1000)
        os.utime(path, (1e9 + age, 1e9 + age))  # made in this order
        made[name] = path
    folder_bag = cache.path("recordings", "ros2", "0123456789abcdef")  # a ROS 2 bag is a folder
    folder_bag.mkdir()
    (folder_bag / "data.mcap").write_bytes(b"x" * 500)
    os.utime(folder_bag, (1e9 + 10, 1e9 + 10))
    new = cache.write(cache.path("recordings", "new", "fedcba9876543210", ".bin"), lambda p: p.write_bytes(b"y" * 1000))
    # 4500 bytes that can be made again beside the new 1000 (the download does not count): the two oldest go
    assert not made["old"].exists() and not made["older-code"].exists()
    assert made["download"].exists() and made["bag2"].exists() and made["run"].exists() and folder_bag.exists()
    assert new.read_bytes() == b"y" * 1000
    assert cache.evict(max_bytes=0) == [made["bag2"], made["run"], folder_bag, new]  # oldest first, keep aside
    assert cache.evict(keep=None, max_bytes=0) == [] and made["download"].exists()


# ------------------------------------------------------------------------------------- damaged after it was made


def tiny_setup() -> Setup:
    """The test preset's first segment seen at 3 frames a second on a small floor: a recording of 6 frames."""
    setup = PRESETS["test"].setup()
    return dataclasses.replace(
        setup,
        rig=dataclasses.replace(setup.rig, rate_hz=3.0),
        plan=MotionPlan(setup.plan.segments[:1]),
        floor_margin_m=1.0,
        texel_m=2e-3,
    )


def truncated(path: Path) -> None:
    """Cut ``path`` to half its bytes, as a crash mid-write or a full disk leaves it."""
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def bit_flipped(path: Path) -> None:
    """One bit of ``path`` turned, a third of the way in, as a bad sector or a bad copy leaves it."""
    data = bytearray(path.read_bytes())
    data[len(data) // 3] ^= 0x10
    path.write_bytes(bytes(data))


def largest_file(path: Path) -> Path:
    """``path``, or the largest file of the folder ``path`` (a ROS 2 bag's storage file)."""
    return max(path.iterdir(), key=lambda p: p.stat().st_size) if path.is_dir() else path


def contents(path: Path) -> dict[str, bytes]:
    """The bytes of the file ``path``, or of every file of the folder ``path``, by name."""
    return {p.name: p.read_bytes() for p in (sorted(path.iterdir()) if path.is_dir() else [path])}


def test_a_file_without_its_seal_or_unlike_it_is_not_intact(tmp_path):
    target = cache.write(tmp_path / "runs" / "run-0123456789abcdef.npz", lambda p: np.savez(p, value=np.arange(3)))
    content = target.read_bytes()
    assert cache.intact(target) and checksum.sealed(target) == {target.name: (zlib.crc32(content), len(content))}
    checksum.seal_path(target).write_text("not a seal\n")
    assert not cache.intact(target)
    checksum.seal_path(target).unlink()  # as a file made before files were sealed
    assert not cache.intact(target)
    cache.write(target, lambda p: np.savez(p, value=np.arange(3)))  # made again, sealed
    assert cache.intact(target) and np.load(target)["value"].tolist() == [0, 1, 2]


@pytest.mark.parametrize(("bag_format", "damage"), [("ros1", truncated), ("ros2", bit_flipped)])
def test_a_damaged_recording_is_rendered_again_never_read(tmp_path, monkeypatch, bag_format, damage):
    monkeypatch.setenv(cache.ENVIRONMENT_VARIABLE, str(tmp_path))
    rendered = []
    simulate = record.simulate
    monkeypatch.setattr(record, "simulate", lambda *args: rendered.append(args) or simulate(*args))
    bag = recording(tiny_setup(), bag_format, progress=False, label="tiny")
    original = contents(bag)
    assert recording(tiny_setup(), bag_format, progress=False, label="tiny") == bag and len(rendered) == 1
    damage(largest_file(bag))
    assert contents(bag) != original and not cache.intact(bag)
    assert recording(tiny_setup(), bag_format, progress=False, label="tiny") == bag
    assert len(rendered) == 2 and contents(bag) == original  # rendered again: the same bag, byte for byte


@pytest.mark.parametrize("damage", [truncated, bit_flipped])
def test_a_damaged_table_is_built_again_never_read(tmp_path, monkeypatch, damage):
    monkeypatch.setenv(cache.ENVIRONMENT_VARIABLE, str(tmp_path))
    rig, floor = t265_rig(), FloorImage.top_view(metres_per_pixel=4e-3)
    table = analytic_table(rig.camera, rig.mount, floor)
    path = cache.path("tables", "table", table.key, ".npz")
    original = path.read_bytes()
    damage(path)
    again = analytic_table(rig.camera, rig.mount, floor)
    assert path.read_bytes() == original and cache.intact(path)
    for name in ("map_x", "map_y", "valid"):
        assert np.array_equal(getattr(again, name), getattr(table, name))


@pytest.mark.parametrize("damage", [truncated, bit_flipped])
def test_a_damaged_floor_run_is_run_again_never_read(tmp_path, monkeypatch, damage):
    monkeypatch.setenv(cache.ENVIRONMENT_VARIABLE, str(tmp_path))
    bag = recording(tiny_setup(), progress=False, label="tiny")
    config = route_config("gpo-exact", "analytic")
    first = floor_run(bag, config)
    [path] = (tmp_path / "runs").glob("*.npz")
    original = path.read_bytes()
    damage(path)
    ran = []
    run = experiment_runs.run
    monkeypatch.setattr(experiment_runs, "run", lambda *args, **kwargs: ran.append(args) or run(*args, **kwargs))
    again = floor_run(bag, config)
    assert len(ran) == 1 and cache.intact(path)  # run again, and kept again
    with np.load(io.BytesIO(original)) as kept, np.load(path) as remade:  # all but the speed it measured
        for name in ("stamps_ns", "poses", "inliers", "spread_px"):
            assert np.array_equal(remade[name], kept[name], equal_nan=True)
    assert np.array_equal(again.trajectory.positions, first.trajectory.positions)
