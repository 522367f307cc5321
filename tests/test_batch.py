"""gpo.batch: sweeps on a local two-worker cluster and on a scheduler and workers started as processes of their own
(127.0.0.1), resumption after a worker is killed mid-sweep, after the scheduler goes away and after the disk fills,
runs and tables damaged after they were written made again, failing runs kept with their error; the numbers checked
against the same run made directly through gpo.pipeline and gpo.metrics."""

import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest
import yaml

import gpo
from gpo.batch.cluster import REACH_TIMEOUT_S, WORKER_ENVIRONMENT_UNSET, cluster_client
from gpo.batch.runs import Run, configured, recording_digest, run_key
from gpo.batch.spec import SweepSpec, load_spec
from gpo.batch.sweep import sweep
from gpo.batch.table import read_table
from gpo.cli import main
from gpo.io.bag import Recording
from gpo.io.bag_writer import BagWriter
from gpo.io.trajectory import Trajectory
from gpo.metrics import final_error
from gpo.pipeline.config import config_to_dict, load_config
from gpo.pipeline.run import run
from gpo.sim.record import GROUND_TRUTH_TOPIC, PRESETS, recording

REPOSITORY = Path(gpo.__file__).resolve().parents[1]
CLUSTER_START_S = 60  # the most a scheduler and its workers may take to come up on a loaded machine


def cut(source: Path, out: Path, start_s: float, seconds: float) -> Path:
    """A bag of the frames and ground truth of ``source`` within [start_s, start_s + seconds): a small recording."""
    with Recording(source) as recorded:
        begin = recorded.start_ns + round(start_s * 1e9)
        end = begin + round(seconds * 1e9)
        topic = recorded.image_topic()
        frames = list(recorded.frames(topic, begin, end, progress=False))
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    within = (truth.stamps_ns >= begin - 10_000_000) & (truth.stamps_ns < end + 10_000_000)
    with BagWriter(out) as bag:
        truth_part = Trajectory(truth.stamps_ns[within], truth.positions[within], truth.quaternions[within])
        bag.add_trajectory(GROUND_TRUTH_TOPIC, truth_part, msgtype="pose")
        for frame in frames:
            bag.add_image(topic, frame.stamp_ns, frame.image, frame.frame_id)
    return out


@pytest.fixture(scope="module")
def bags(tmp_path_factory) -> dict[str, str]:
    """The ``test`` preset and two one-second pieces of it, and a file that is no bag."""
    folder = tmp_path_factory.mktemp("bags")
    test = recording("test", progress=False)
    (folder / "garbage.bag").write_bytes(b"not a bag at all\n" * 10)
    return {
        "test": str(test),
        "early": str(cut(test, folder / "early.bag", 0.2, 1.0)),
        "late": str(cut(test, folder / "late.bag", 1.8, 1.0)),
        "garbage": str(folder / "garbage.bag"),
    }


def direct_final_error_m(bag: str, overrides: dict) -> float:
    """The same run made without gpo.batch: gpo.pipeline.run, then gpo.metrics.final_error."""
    config = configured(Run(bag, "direct", overrides=overrides))
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    return final_error(run(bag, config, progress=False).trajectory, truth).position_m


# ----------------------------------------------------------------------------------------------- without a cluster


def test_overrides_go_through_the_config_schema():
    config = configured(Run("unused.bag", "x", overrides={"klt.window_px": 15, "odometry.method": "gpo-rigid"}))
    assert (config.klt.window_px, config.method) == (15, "gpo-rigid")
    assert config.klt.max_corners == load_config().klt.max_corners  # the rest as the base config says
    with pytest.raises(ValueError, match=r"^the default config with klt\.window changed: klt\.window: unknown key; "
                                         r"did you mean window_px\?"):  # no temporary file named
        configured(Run("unused.bag", "x", overrides={"klt.window": 15}))
    with pytest.raises(ValueError, match=r"override mount\.pitch_deg: 3\.0 has no effect"):
        configured(Run("unused.bag", "x", overrides={"mount.pitch_deg": 3.0}))


def test_the_key_follows_recording_content_config_and_code(tmp_path):
    one, other = tmp_path / "a.bag", tmp_path / "b.bag"
    one.write_bytes(b"same")
    other.write_bytes(b"same")
    assert recording_digest(str(one)) == recording_digest(str(other))  # content, not name
    document = config_to_dict(load_config())
    changed = config_to_dict(load_config().replace(method="gpo"))
    keys = [run_key("r", document, "v"), run_key("r", changed, "v"), run_key("s", document, "v")]
    assert len({*keys, run_key("r", document, "w")}) == 4
    with pytest.raises(FileNotFoundError, match="no such recording"):
        recording_digest(str(tmp_path / "missing.bag"))


def test_spec_expands_to_the_grid_and_names_its_errors(tmp_path):
    (tmp_path / "a.bag").write_bytes(b"x")
    (tmp_path / "b.bag").write_bytes(b"x")
    spec_path = tmp_path / "sweep.yaml"
    spec_path.write_text(
        yaml.safe_dump(
            {
                "recordings": [{"glob": "*.bag"}, {"preset": "test", "seeds": [4, 5]}],
                "set": {"odometry.vector": "median"},
                "vary": {"klt.window_px": [15, 21, 31], "odometry.method": ["gpo", "gpo-exact"]},
                "runs": [{"klt.max_corners": 100}, {"klt.max_corners": 200}],
            }
        )
    )
    spec = load_spec(spec_path)
    assert spec.presets() == [("test", 4), ("test", 5)]
    runs = spec.expand({("test", 4): "/x/t4.bag", ("test", 5): "/x/t5.bag"})
    assert len(runs) == 4 * 2 * 3 * 2
    assert [r.label for r in runs[::12]] == ["a.bag", "b.bag", "test@4", "test@5"]
    assert runs[0].recording == str(tmp_path / "a.bag")
    assert runs[0].overrides == {"odometry.vector": "median", "klt.max_corners": 100, "klt.window_px": 15,
                                 "odometry.method": "gpo"}
    spec_path.write_text("recordings: [{file: a.bag}]\nvarry: {klt.window_px: [1]}\n")
    with pytest.raises(ValueError, match=r"sweep.yaml: varry: Extra inputs are not permitted"):
        load_spec(spec_path)
    with pytest.raises(ValueError, match=r"glob .*nothing\*\.bag matches no file"):
        SweepSpec(recordings=[{"glob": str(tmp_path / "nothing*.bag")}]).expand()


def _sweep_spec(folder: Path, **changes) -> Path:
    """A spec of one recording file (never opened by the checks) and a valid grid, with ``changes``."""
    spec = folder / "sweep.yaml"
    document = {"recordings": [{"file": "hall.bag"}], "vary": {"klt.window_px": [15, 21]}} | changes
    spec.write_text(yaml.safe_dump(document))
    return spec


@pytest.mark.parametrize(
    ("case", "words"),
    [
        ("file", ["--out {folder}/notes.txt is a file; expected a folder for the results"]),
        ("spec", ["--out {folder}/sweep.yaml is an input of this command"]),
        ("read-only", ["--out {folder}/locked/results: the folder {folder}/locked cannot be written (read-only)"]),
        ("vary", ["{folder}/sweep.yaml: the default config with klt.window changed: klt.window: unknown key; did you "
                  "mean window_px?"]),
        ("range", ["{folder}/sweep.yaml: the default config with klt.window_px changed: klt.window_px must be an odd "
                   "whole number from 5 to 101 px, got 4"]),
        ("scheduler", ["--scheduler tcp://127.0.0.1:1: no Dask scheduler there (connection refused)",
                       "dask scheduler --port 1", "leave out --scheduler"]),
    ],
)
def test_the_sweep_command_checks_its_inputs_before_the_cluster_starts(tmp_path, capsys, monkeypatch, case, words):
    """Each refused at once, with the spec, the option or the address named (before: after the cluster started,
    with a raw [Errno 20/30], a deleted temporary file's name, or a 22 s wait and "Timed out")."""
    import distributed

    monkeypatch.setattr(distributed, "LocalCluster", lambda *a, **k: pytest.fail("a cluster was started"))
    (tmp_path / "notes.txt").write_text("notes\n")
    (tmp_path / "locked").mkdir()
    real_access = os.access
    monkeypatch.setattr(os, "access", lambda path, mode: Path(path) != tmp_path / "locked" and real_access(path, mode))
    changes = {"vary": {"vary": {"klt.window": [15]}}, "range": {"vary": {"klt.window_px": [15, 4]}}}.get(case, {})
    spec = _sweep_spec(tmp_path, **changes)
    out = {"file": "notes.txt", "spec": "sweep.yaml", "read-only": "locked/results"}.get(case, "results")
    argv = ["sweep", str(spec), "--out", str(tmp_path / out)]
    argv += ["--scheduler", "tcp://127.0.0.1:1"] if case == "scheduler" else []
    started = time.monotonic()
    assert main(argv) == 1
    seconds = time.monotonic() - started
    err = capsys.readouterr().err
    for word in words:
        assert word.format(folder=tmp_path) in err, err
    assert "Traceback" not in err and "Errno" not in err and "/tmp/tmp" not in err
    assert not (tmp_path / "results").exists() and (tmp_path / "notes.txt").read_text() == "notes\n"
    assert seconds < REACH_TIMEOUT_S + 5  # the probe's timeout and the checks' own time, never Dask's 20 s wait


def test_a_preset_with_its_own_seed_is_the_preset(bags):
    assert recording("test", seed=PRESETS["test"].seed, progress=False) == Path(bags["test"])


# ----------------------------------------------------------------------------------------------- local cluster


def stop(row: dict) -> None:
    """Ctrl-C at the first finished run."""
    raise KeyboardInterrupt


def test_sweep_on_a_local_cluster_keeps_failures_and_resumes(bags, tmp_path):
    good = [
        Run(bags["early"], "early", overrides={"klt.window_px": 15}),
        Run(bags["early"], "early", overrides={"klt.window_px": 21}),
        Run(bags["late"], "late", overrides={"odometry.method": "gpo-rigid"}),
        Run(bags["test"], "test"),
    ]
    failing = [
        Run(bags["late"], "late", overrides={"odometry.method": "nope"}),  # refused by the config's schema
        Run(bags["garbage"], "garbage"),  # not a bag
        Run(str(Path(bags["garbage"]).with_name("missing.bag")), "missing"),
    ]
    out = tmp_path / "results"
    with cluster_client(workers=2) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        # glibc's adaptive mmap threshold stays on (Dask's nanny would set MALLOC_TRIM_THRESHOLD_ and slow runs 1.8x)
        assert set(client.run(lambda: WORKER_ENVIRONMENT_UNSET[0] in os.environ).values()) == {False}
        first = sweep(good[:2], out, client, progress=False)
        assert len(first.executed) == 2 and first.reused == []
        second = sweep(good + failing, out, client, progress=False)
        third = sweep(good + failing, out, client, progress=False)
        interrupted = [Run(bags["late"], "late", overrides={"klt.window_px": w}) for w in (15, 31)]
        with pytest.raises(KeyboardInterrupt):
            sweep(interrupted, tmp_path / "interrupted", client, progress=False, on_result=stop)
        kept = read_table(tmp_path / "interrupted")  # the table holds the run finished before Ctrl-C
        resumed = sweep(interrupted, tmp_path / "interrupted", client, progress=False)
    assert len(kept) == 1 and resumed.reused == kept["key"].tolist() and len(resumed.executed) == 1
    assert sorted(second.reused) == sorted(first.executed)  # the finished runs were not run again
    assert len(second.executed) == 2 + 3
    assert len(third.reused) == 4
    assert len(third.executed) == 3  # only the failed ones are tried again
    table = read_table(out)
    assert len(table) == 7
    assert pd.read_csv(out / "results.csv")["key"].tolist() == table["key"].tolist()
    errors = dict(zip(table["recording"] + ":" + table["status"], table["error"], strict=True))
    assert "unknown method 'nope'" in errors["late:failed"]
    assert "garbage.bag" in errors["garbage:failed"]
    assert "missing.bag: no such recording" in errors["missing:failed"]
    ok = table[table["status"] == "ok"].set_index("key")
    # measured 0.004 to 0.21 % (late, gpo-rigid); each of the short pieces has 30 frames, the test preset 97
    assert len(ok) == 4 and (ok["final_error_percent"] < 0.5).all() and (ok["frames"] >= 30).all()
    assert (ok["recording_sha256"].str.len() == 64).all() and ok["code_version"].nunique() == 1
    row = table[(table["recording"] == "early") & (table["param.klt.window_px"] == 15)].iloc[0]
    assert row["final_error_m"] == pytest.approx(direct_final_error_m(bags["early"], {"klt.window_px": 15}), abs=1e-12)
    kept = out / "runs" / row["key"]
    assert Trajectory.read_tum(kept / "trajectory.tum").stamps_ns.size == row["frames"]
    assert load_config(kept / "config.yaml").klt.window_px == 15


# ----------------------------------------------------------------------------------------------- a cluster by address


class ProcessCluster:
    """A Dask scheduler and ``workers`` single-threaded workers, each a process of its own on 127.0.0.1, each in a
    session of its own so that it and its children are ended whatever happens."""

    def __init__(self, folder: Path, workers: int):
        self.folder = folder
        self.scheduler_file = folder / "scheduler.json"
        self.environment = {**os.environ, "PYTHONPATH": str(REPOSITORY)}
        self.scheduler = self._start(
            ["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
             "--scheduler-file", str(self.scheduler_file)], "scheduler"
        )
        self.workers = [self.start_worker(k) for k in range(workers)]

    def _start(self, arguments: list[str], name: str) -> subprocess.Popen:
        log = (self.folder / f"{name}.log").open("w")
        return subprocess.Popen(
            [sys.executable, "-m", *arguments], env=self.environment, stdout=log, stderr=subprocess.STDOUT,
            start_new_session=True, cwd=self.folder,
        )

    def start_worker(self, index: int) -> subprocess.Popen:
        deadline = time.monotonic() + CLUSTER_START_S
        while not self.scheduler_file.exists():
            assert self.scheduler.poll() is None, (self.folder / "scheduler.log").read_text()
            assert time.monotonic() < deadline, "the scheduler did not start"
            time.sleep(0.2)
        return self._start(
            ["distributed.cli.dask_worker", "--scheduler-file", str(self.scheduler_file), "--nthreads", "1",
             "--no-dashboard", "--no-nanny", "--host", "127.0.0.1", "--name", f"worker-{index}"], f"worker-{index}"
        )

    @property
    def address(self) -> str:
        return yaml.safe_load(self.scheduler_file.read_text())["address"]

    def wait_for_workers(self, client, count: int) -> None:
        client.wait_for_workers(count, timeout=CLUSTER_START_S)

    @staticmethod
    def kill(process: subprocess.Popen) -> None:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
        process.wait(timeout=10)

    def close(self) -> None:
        for process in (*self.workers, self.scheduler):
            self.kill(process)


@pytest.fixture
def process_cluster(tmp_path):
    cluster = ProcessCluster(tmp_path, workers=2)
    try:
        yield cluster
    finally:
        cluster.close()


def test_sweep_command_against_a_scheduler_address(bags, process_cluster, tmp_path, capsys):
    spec = tmp_path / "sweep.yaml"
    spec.write_text(
        yaml.safe_dump(
            {
                "recordings": [{"file": bags["early"]}, {"file": bags["late"]}],
                "vary": {"odometry.method": ["gpo-exact", "gpo-rigid"]},
            }
        )
    )
    out = tmp_path / "results"
    with cluster_client(process_cluster.address) as client:
        process_cluster.wait_for_workers(client, 2)
    assert main(["sweep", str(spec), "--out", str(out), "--scheduler", process_cluster.address]) == 0
    printed = capsys.readouterr().out
    assert "4 runs done now, 0 already done before, 0 failed" in printed
    table = read_table(out)
    assert table["status"].tolist() == ["ok"] * 4
    methods = table.groupby("recording")["param.odometry.method"].apply(sorted).tolist()
    assert methods == [["gpo-exact", "gpo-rigid"]] * 2
    rigid_late = table[(table["recording"] == "late.bag") & (table["param.odometry.method"] == "gpo-rigid")].iloc[0]
    expected = direct_final_error_m(bags["late"], {"odometry.method": "gpo-rigid"})
    assert rigid_late["final_error_m"] == pytest.approx(expected, abs=1e-12)
    assert main(["sweep", str(spec), "--out", str(out), "--scheduler", process_cluster.address]) == 0
    assert "0 runs done now, 4 already done before" in capsys.readouterr().out
    assert main(["sweep-report", str(out)]) == 0
    png = out / "report" / "error_vs_odometry_method.png"
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_a_worker_killed_mid_sweep(bags, process_cluster, tmp_path):
    runs = [Run(bags[name], name, overrides={"klt.window_px": w}) for name in ("early", "late") for w in (15, 21)]
    out = tmp_path / "results"
    killed = []

    with cluster_client(process_cluster.address) as client:
        process_cluster.wait_for_workers(client, 2)

        def kill_a_busy_worker(row: dict) -> None:
            if killed:
                return
            names = {address: w["name"] for address, w in client.scheduler_info()["workers"].items()}
            busy = [names[address] for address, tasks in client.processing().items() if tasks]
            if busy:
                process_cluster.kill(process_cluster.workers[int(busy[0].removeprefix("worker-"))])
                killed.append(busy[0])

        result = sweep(runs, out, client, progress=False, on_result=kill_a_busy_worker)
        assert killed and len(client.scheduler_info()["workers"]) == 1
        again = sweep(runs, out, client, progress=False)
    assert sorted(result.executed) == sorted(set(result.executed)) and len(result.executed) == 4
    assert result.table["status"].tolist() == ["ok"] * 4  # the run lost with its worker was run again elsewhere
    assert again.executed == [] and sorted(again.reused) == sorted(result.executed)
    for _, row in result.table.iterrows():  # each run's number, the lost one's too, as the run made directly gives it
        expected = direct_final_error_m(bags[row["recording"]], {"klt.window_px": int(row["param.klt.window_px"])})
        assert row["final_error_m"] == pytest.approx(expected, abs=1e-12), row["key"]


# ----------------------------------------------------------------------------------------------- faults


def truncated(path: Path) -> None:
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def bit_flipped(path: Path) -> None:
    data = bytearray(path.read_bytes())
    data[len(data) // 3] ^= 0x10
    path.write_bytes(bytes(data))


def test_runs_and_a_table_damaged_after_the_sweep_are_made_again(bags, tmp_path):
    runs = [Run(bags["early"], "early", overrides={"klt.window_px": w}) for w in (15, 21, 31)]
    out = tmp_path / "results"
    with cluster_client(workers=1) as client:
        first = sweep(runs, out, client, progress=False)
        keys = sorted(first.executed)
        truncated(out / "runs" / keys[0] / "row.json")  # a crash mid-write on another machine
        bit_flipped(out / "runs" / keys[1] / "trajectory.tum")  # a bad copy
        again = sweep(runs, out, client, progress=False)
    assert sorted(again.executed) == keys[:2] and again.reused == [keys[2]]  # the damaged runs, run again
    columns = ["key", "status", "frames", "final_error_m", "ape_rmse_m"]
    assert again.table[columns].equals(first.table[columns])  # the same numbers: the runs are deterministic
    bit_flipped(out / "results.parquet")
    assert read_table(out)[columns].equals(first.table[columns])  # made again from the runs' rows


def test_a_full_disk_stops_the_sweep_keeping_every_finished_run(bags, tmp_path, monkeypatch):
    runs = [Run(bags["early"], "early", overrides={"klt.window_px": w}) for w in (15, 21, 31)]
    out = tmp_path / "results"
    write_text, kept = Path.write_text, []

    def full_at_the_second_row(path: Path, text: str, *args, **kwargs):
        if path.name == "row.json" and len(kept) == 1:
            write_text(path, text[: len(text) // 2])  # what fitted
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        if path.name == "row.json":
            kept.append(path)
        return write_text(path, text, *args, **kwargs)

    with cluster_client(workers=1) as client:
        monkeypatch.setattr(Path, "write_text", full_at_the_second_row)
        with pytest.raises(OSError, match="No space left on device") as stopped:
            sweep(runs, out, client, progress=False)
        monkeypatch.undo()
        left = sorted(path.name for path in (out / "runs").iterdir())
        table = read_table(out)
        resumed = sweep(runs, out, client, progress=False)
    message = str(stopped.value)
    assert "every run finished before it is kept in" in message and str(out) in message and "make room" in message
    assert len(table) == 1 and left == [table["key"][0], f"{table['key'][0]}.crc32"]  # the half-written run: gone
    assert resumed.reused == table["key"].tolist() and len(resumed.executed) == 2
    assert resumed.table["status"].tolist() == ["ok"] * 3


def test_the_scheduler_going_away_stops_the_sweep_keeping_every_finished_run(bags, tmp_path):
    runs = [Run(bags[name], name, overrides={"klt.window_px": w}) for name in ("early", "late") for w in (15, 21)]
    out = tmp_path / "results"
    first_cluster = ProcessCluster(tmp_path, workers=1)
    try:
        with cluster_client(first_cluster.address) as client:
            first_cluster.wait_for_workers(client, 1)

            def scheduler_gone(row: dict) -> None:
                first_cluster.kill(first_cluster.scheduler)

            gone = r"the Dask scheduler went away \(1 of this sweep's runs finished before\)"
            with pytest.raises(ConnectionError, match=gone):
                sweep(runs, out, client, progress=False, on_result=scheduler_gone)
    finally:
        first_cluster.close()
    kept = read_table(out)
    (tmp_path / "second").mkdir()
    second_cluster = ProcessCluster(tmp_path / "second", workers=2)
    try:
        with cluster_client(second_cluster.address) as client:
            second_cluster.wait_for_workers(client, 2)
            resumed = sweep(runs, out, client, progress=False)
    finally:
        second_cluster.close()
    assert kept["status"].tolist() == ["ok"]  # the run finished before the scheduler went away
    assert resumed.reused == kept["key"].tolist() and len(resumed.executed) == 3
    assert resumed.table["status"].tolist() == ["ok"] * 4
