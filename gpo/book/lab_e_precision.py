"""Lab E, why numbers print at their precision: one sum in several orders and widths, the same computations on two
floating-point paths of this machine (``.ci/fp-path``, each in a process of its own), a run repeated with its frames
changed by one grey level, and a calibration's digits against its uncertainty.

``python -m gpo.book.lab_e_precision PATH FOLDER`` is what ``probe_paths`` starts under ``.ci/fp-path PATH``: it writes
``FOLDER/PATH.npz`` with what that path computes (``probe``).
"""

from __future__ import annotations

import ctypes
import json
import math
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import matplotlib.pyplot as plt
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
FP_PATH = ROOT / ".ci" / "fp-path"
PATHS = ("avx2", "sse4")
RECORDING = "sample"  # the recording of chapters 05-06
CHANGED_PIXELS = 40  # pixels of a frame changed by one grey level, about as many as rendering on sse4 changes
CHANGED_RUNS = 3  # runs of the kept recording with CHANGED_PIXELS changed in every frame, each with its seed
CALIBRATION_VIEWS, CALIBRATION_NOISE_PX = 24, 0.3  # chapter 01's calibration: views of its board, corner noise
OPENCV_FEATURES = {"SSE4_2": 7, "AVX": 10, "AVX2": 11, "AVX512_SKX": 256}  # OpenCV's CPU feature ids
NUMPY_TARGETS = ("X86_V2", "X86_V3", "X86_V4", "AVX512_ICL", "AVX512_SPR")  # NumPy's x86-64 dispatch levels


def fp_path_settings(script: Path = FP_PATH) -> dict[str, dict[str, str]]:
    """What ``.ci/fp-path`` exports for each path: path -> {variable: value}, read from the script itself."""
    settings, path = {}, None
    for line in script.read_text().splitlines():
        case = re.match(r"^(\w+)\)$", line.strip())
        if case:
            path = case.group(1)
            settings[path] = {}
        export = re.match(r'^export (\w+)="?([^"]*)"?$', line.strip())
        if export and path:
            settings[path][export.group(1)] = export.group(2)
    return settings


def machine() -> dict[str, str]:
    """The floating-point path this process takes: OpenBLAS's kernels (its core name), the widest of NumPy's dispatch
    targets in use and the widest of OpenCV's SIMD levels enabled."""
    library = next((Path(np.__file__).parent.parent / "numpy.libs").glob("libscipy_openblas*"), None)
    core = "unknown"
    if library is not None:
        openblas = ctypes.CDLL(str(library))
        for name in ("scipy_openblas_get_corename64_", "scipy_openblas_get_corename", "openblas_get_corename"):
            if hasattr(openblas, name):
                getattr(openblas, name).restype = ctypes.c_char_p
                core = getattr(openblas, name)().decode()
                break
    from numpy._core._multiarray_umath import __cpu_features__

    numpy_targets = [target for target in NUMPY_TARGETS if __cpu_features__.get(target)]
    opencv = [name for name, feature in OPENCV_FEATURES.items() if cv2.checkHardwareSupport(feature)]
    return {
        "OpenBLAS kernels": core,
        "NumPy's widest loops": numpy_targets[-1] if numpy_targets else "baseline",
        "OpenCV's widest loops": opencv[-1] if opencv else "baseline",
    }


def changed(image: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """A copy of the uint8 ``image`` with ``count`` pixels, drawn by ``rng``, one grey level up or down (up from 0,
    down from 255): what rendering the same frame on another floating-point path does to a few of its pixels."""
    out = image.copy()
    flat = out.reshape(-1)
    where = rng.choice(flat.size, count, replace=False)
    step = rng.choice(np.array([-1, 1], dtype=np.int16), count)
    step[flat[where] == 0], step[flat[where] == 255] = 1, -1
    flat[where] = (flat[where].astype(np.int16) + step).astype(np.uint8)
    return out


def run_poses(stamps_ns, images) -> np.ndarray:
    """The shipped config's floor odometry over ``images`` (frames at ``stamps_ns``): base_link's pose (x, y, theta)
    in odom after every frame, (N, 3)."""
    from gpo.pipeline.config import load_config
    from gpo.pipeline.odometer import FloorOdometer

    odometer = FloorOdometer(load_config())
    poses = []
    for stamp, image in zip(stamps_ns, images, strict=True):
        odometer.step(int(stamp), image)
        poses.append(odometer.pose)
    return np.array(poses)


def recorded_frames(name: str = RECORDING) -> tuple[np.ndarray, list[np.ndarray]]:
    """The kept recording ``name`` (made once, by this machine's own path): its frames' stamps (ns) and images."""
    from gpo.io.bag import Recording
    from gpo.sim.record import recording

    with Recording(recording(name, progress=False)) as bag:
        frames = [(frame.stamp_ns, frame.image) for frame in bag.frames(progress=False)]
    return np.array([stamp for stamp, _ in frames]), [image for _, image in frames]


def calibration_fit():
    """Chapter 01's calibration from corners: the EUCM fitted to ``CALIBRATION_VIEWS`` views of its board, every
    corner moved by ``CALIBRATION_NOISE_PX`` of seeded noise (a ``gpo.cameras.calibrate.CalibrationResult``)."""
    from gpo.cameras.calibrate import calibrate_corners
    from gpo.sim.boardviews import CALIBRATION_BOARD, board_poses
    from gpo.sim.rigs import t265_rig

    truth = t265_rig().camera
    rng = np.random.default_rng(0)
    corners = []
    for rotation, position in board_poses(truth, CALIBRATION_VIEWS, CALIBRATION_BOARD, seed=7):
        projected, _ = truth.project(rotation.apply(CALIBRATION_BOARD.inner_corners()) + position)
        corners.append(projected + rng.normal(0.0, CALIBRATION_NOISE_PX, projected.shape))
    return calibrate_corners(corners, CALIBRATION_BOARD, (truth.width, truth.height), "eucm")


def probe(path: str, folder: Path) -> Path:
    """What the path this process takes computes, in ``folder/PATH.npz``: ``machine``; a product of a seeded
    300 x 300 matrix with its transpose (OpenBLAS); the calibration's parameters and their standard deviations; the
    poses of the floor odometry over the kept recording, and its frames' stamps. On ``sse4`` also the recording
    rendered again here (how many pixels of each frame differ from the kept one) and the run over it; on ``avx2`` the
    true poses (``true_poses``) and the runs over the kept frames with ``CHANGED_PIXELS`` pixels changed in each
    (``CHANGED_RUNS`` seeds)."""
    from gpo.sim.record import Scene

    a = np.random.default_rng(1).normal(size=(300, 300))
    fit = calibration_fit()
    stamps, images = recorded_frames()
    found = {
        "machine": json.dumps(machine()),
        "product": a @ a.T,
        "parameters": np.array(list(fit.params.values())),
        "sigmas": np.array([fit.std[name] for name in fit.params]),
        "names": np.array(list(fit.params)),
        "kept": run_poses(stamps, images),
        "stamps": stamps,
    }
    if path == "sse4":
        scene = Scene.of(RECORDING)
        rendered = [scene.frame(index) for index in range(len(images))]
        found["pixels_differing"] = np.array([np.count_nonzero(a != b) for a, b in zip(rendered, images, strict=True)])
        found["rendered"] = run_poses(stamps, rendered)
    if path == "avx2":
        found["truth"] = true_poses(stamps)
        for seed in range(CHANGED_RUNS):
            rng = np.random.default_rng(seed)
            found[f"changed {seed}"] = run_poses(stamps, [changed(image, CHANGED_PIXELS, rng) for image in images])
    out = Path(folder) / f"{path}.npz"
    np.savez(out, **found)
    return out


def probe_paths(paths=PATHS) -> dict[str, dict]:
    """``probe`` run under ``.ci/fp-path PATH`` for each of ``paths``, side by side, each in a process of its own
    (one thread each): path -> what it computed (``machine`` as a dict)."""
    if not FP_PATH.is_file():
        raise FileNotFoundError(f"{FP_PATH} is not here: the floating-point paths are the checkout's, not the wheel's")
    environment = os.environ | {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENCV_FOR_THREADS_NUM": "1"}
    with tempfile.TemporaryDirectory() as folder:
        started = {
            path: subprocess.Popen(
                [str(FP_PATH), path, sys.executable, "-m", __name__, path, folder],
                env=environment,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )
            for path in paths
        }
        found = {}
        for path, process in started.items():
            _, errors = process.communicate()
            if process.returncode:
                raise RuntimeError(f"the probe on the {path} path failed:\n{errors}")
            with np.load(Path(folder) / f"{path}.npz") as data:
                found[path] = {key: data[key] for key in data.files}
            found[path]["machine"] = json.loads(str(found[path]["machine"]))
    return found


def sums(values: np.ndarray) -> dict[str, float]:
    """The sum of ``values`` (float64) computed six ways: exactly (``math.fsum``), one after the other in float64,
    in reverse order, pairwise as ``np.sum`` adds, and one after the other and pairwise in float32."""
    single = values.astype(np.float32)
    return {
        "exact (math.fsum)": math.fsum(values),
        "float64, in order": float(np.cumsum(values)[-1]),
        "float64, reversed": float(np.cumsum(values[::-1])[-1]),
        "float64, pairwise (np.sum)": float(np.sum(values)),
        "float32, in order": float(np.cumsum(single)[-1]),
        "float32, pairwise (np.sum)": float(np.sum(single)),
    }


def agreeing_digits(value: float, exact: float) -> int:
    """How many leading significant digits ``value`` shares with ``exact`` (both printed with 17)."""
    shown, truth = f"{value:.16e}", f"{exact:.16e}"
    if shown[-4:] != truth[-4:]:  # another power of ten
        return 0
    digits = [(a, b) for a, b in zip(shown[:18], truth[:18], strict=True) if a != "."]
    return next((k for k, (a, b) in enumerate(digits) if a != b), len(digits))


def running_errors(values: np.ndarray, at: np.ndarray) -> dict[str, np.ndarray]:
    """The relative error of the in-order running sum of ``values`` after each count in ``at``, in float64 and float32,
    against the exact sum of as many (``math.fsum``)."""
    exact = np.array([math.fsum(values[:count]) for count in at])
    return {
        "float64": np.abs(np.cumsum(values)[at - 1] - exact) / exact,
        "float32": np.abs(np.cumsum(values.astype(np.float32))[at - 1].astype(np.float64) - exact) / exact,
    }


def draw_runs(times_s, runs: dict[str, np.ndarray], finals: dict[str, float]) -> plt.Figure:
    """Left: how far each run of ``runs`` (name -> poses (N, 3) at ``times_s``) lies from the first, in position, over
    time (log scale); right: each run's final position error (``finals``, name -> mm) on one axis."""
    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 4.4), gridspec_kw={"width_ratios": [1.5, 1]})
    (first, reference), *others = runs.items()
    for k, (name, poses) in enumerate(others, start=1):
        apart = np.hypot(*(poses[:, :2] - reference[:, :2]).T) * 1e6
        left.semilogy(times_s, np.where(apart > 0, apart, np.nan), color=f"C{k}", lw=1, label=name)
    left.set(xlabel="time [s]", ylabel="position apart [µm]", title=f"each run against '{first}'")
    left.legend(fontsize="small")
    for k, error_mm in enumerate(finals.values()):
        right.plot(error_mm, k, "o", color=f"C{k}" if k else "black")
    right.set_yticks(range(len(finals)), list(finals))
    right.invert_yaxis()
    right.set(xlabel="final position error [mm]", title="where each run ends, against the truth")
    fig.tight_layout()
    return fig


def true_poses(stamps_ns, name: str = RECORDING) -> np.ndarray:
    """base_link's true pose (x, y, theta) in the kept recording ``name`` at each of ``stamps_ns``, relative to the
    first: where the odometry should be after every frame, (N, 3)."""
    from gpo.io.bag import Recording
    from gpo.metrics import truth_poses
    from gpo.odometry.kinematics import between
    from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

    with Recording(recording(name, progress=False)) as bag:
        truth = truth_poses(bag.trajectory(GROUND_TRUTH_TOPIC), np.asarray(stamps_ns) * 1e-9)
    return np.array([between(truth[0], pose) for pose in truth])


def main(arguments: list[str]) -> None:
    path, folder = arguments
    probe(path, Path(folder))


if __name__ == "__main__":
    main(sys.argv[1:])
