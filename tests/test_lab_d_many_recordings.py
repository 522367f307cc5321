"""Lab D's helpers: what a sweep's folder keeps, and the saved sweep-speed measurement told and drawn."""

import matplotlib.pyplot as plt

from gpo.book.lab_d_many_recordings import draw_sweep_speed, kept_files, speed_text

SPEED = {
    "runs": 24,
    "preset": "test",
    "workers": 2,
    "cores": 2,
    "repeats": 3,
    "sequential_s": 4.6,
    "sweep_s": 3.34,
    "cluster_start_s": 1.95,
    "speedup": 1.38,
    "sequential_one_thread_s": 5.87,
    "speedup_over_one_thread": 1.76,
    "speedup_bound": 1.57,
    "overhead_per_run_s": 0.055,
    "overhead_percent_of_a_minute": 0.09,
    "mean_run_s_on_workers": 0.22,
    "identical_results": True,
    "speedups_each_repeat": [1.29, 1.26, 1.45],
}


def test_a_sweeps_folder_is_listed_with_each_runs_key_written_key(tmp_path):
    for key in ("0123abcd", "4567ef01"):
        (tmp_path / "runs" / key).mkdir(parents=True)
        (tmp_path / "runs" / key / "row.json").write_text("{}")
        (tmp_path / "runs" / f"{key}.crc32").write_text("0")
    (tmp_path / "results.csv").write_text("")
    assert kept_files(tmp_path) == ["results.csv", "runs/KEY.crc32", "runs/KEY/row.json"]


def test_the_speed_is_told_against_its_targets():
    lines = speed_text(SPEED).splitlines()
    assert lines[0] == "24 runs of the test recording, 3 repeats (medians), 2 workers on 2 cores"
    assert lines[4].startswith("speed-up 1.38 = 4.60 s / 3.34 s, the ratio of the medians (target 1.8: missed)")
    assert lines[5] == "speed-up of each repeat: 1.29 1.26 1.45 (their median 1.29)"
    assert lines[6].startswith("estimated bound 1.57 = 2 workers x 4.60 s / 5.87 s")
    assert "(target under 5 %: met), 25 % of one of these runs (0.220 s on a worker)" in lines[7]
    assert lines[8].endswith("True")


def test_the_speed_is_drawn_as_times_and_repeats():
    figure = draw_sweep_speed(SPEED)
    times, repeats = figure.axes
    assert len(times.patches) == 4  # three wall times and the cluster's start
    assert list(repeats.lines[0].get_ydata()) == [1.29, 1.26, 1.45]
    assert [line.get_label() for line in repeats.lines[1:3]] == [
        "ratio of the median times",
        "estimated bound (from the medians)",
    ]
    plt.close(figure)
