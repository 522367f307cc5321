"""A sweep's spec (its YAML file): the recordings (files, globs, simulator presets with seeds), the base config and
the parameters to vary, checked by one schema; expanded into the runs of the grid.
"""

from __future__ import annotations

import glob
import itertools
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from gpo.batch.runs import TRUTH_TOPIC, Run, configured
from gpo.cameras.files import read_yaml


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class FileSource(_Strict):
    """A recording file (or ROS 2 bag folder)."""

    file: str
    label: str | None = None


class GlobSource(_Strict):
    """Every recording a glob pattern matches (sorted), each labelled by its file name."""

    glob: str


class PresetSource(_Strict):
    """A simulator preset, rendered (or read from the cache) with each of ``seeds`` (none: its own seed)."""

    preset: str
    seeds: list[int] | None = None


class SweepSpec(_Strict):
    """A sweep as a YAML file says it (relative paths are relative to that file)::

        recordings:                      # files, globs and simulator presets
          - preset: test
            seeds: [1, 2]
          - file: /shared/bags/hall.bag
          - glob: /shared/bags/fleet/*.bag
        config: rig.yaml                 # the base config (default: the shipped simulated T265 rig)
        set: {odometry.method: gpo-exact}      # changes every run makes
        vary:                            # the grid: every combination of these
          klt.window_px: [15, 21, 31]
          odometry.method: [gpo, gpo-exact]
        runs: [{klt.max_corners: 100}, {klt.max_corners: 200}]   # a list of changes, each crossed with the grid
        truth_topic: /mocap/base_link    # the ground truth in every recording
        topic: null                      # the image topic (default: the config's)
    """

    recordings: list[FileSource | GlobSource | PresetSource] = Field(min_length=1)
    config: str | None = None
    set: dict[str, Any] = Field(default_factory=dict)
    vary: dict[str, list[Any]] = Field(default_factory=dict)
    runs: list[dict[str, Any]] = Field(default_factory=lambda: [{}])
    truth_topic: str = TRUTH_TOPIC
    topic: str | None = None

    def presets(self) -> list[tuple[str, int | None]]:
        """The (preset, seed) pairs the spec names, in order."""
        return [
            (source.preset, seed)
            for source in self.recordings
            if isinstance(source, PresetSource)
            for seed in (source.seeds or [None])
        ]

    def expand(self, preset_paths: dict[tuple[str, int | None], str] | None = None) -> list[Run]:
        """The runs: every recording x every set of overrides (``set``, then a ``runs`` entry, then a grid point).
        ``preset_paths`` gives the bag of each of ``presets()``. Raises ValueError for a glob that matches nothing."""
        recordings = []
        for source in self.recordings:
            if isinstance(source, FileSource):
                recordings.append((source.file, source.label or Path(source.file).name))
            elif isinstance(source, GlobSource):
                matched = sorted(glob.glob(source.glob))
                if not matched:
                    raise ValueError(f"recordings: glob {source.glob} matches no file")
                recordings += [(path, Path(path).name) for path in matched]
            else:
                for seed in source.seeds or [None]:
                    label = source.preset if seed is None else f"{source.preset}@{seed}"
                    recordings.append((str((preset_paths or {})[(source.preset, seed)]), label))
        return [
            Run(path, label, self.config, changes, self.truth_topic, self.topic)
            for path, label in recordings
            for changes in self.overrides()
        ]

    def overrides(self) -> list[dict[str, Any]]:
        """The changes of each run of a recording: ``set``, then a ``runs`` entry, then a point of the ``vary`` grid."""
        grid = [dict(zip(self.vary, values, strict=True)) for values in itertools.product(*self.vary.values())]
        return [{**self.set, **entry, **point} for entry in self.runs for point in grid]

    def check_configs(self, where) -> None:
        """Every run's config made once (``configured``) before any run: a ValueError naming ``where`` (the spec's
        file) and the key of ``set``, ``vary`` or ``runs`` that the config refuses, so that a wrong key stops the
        sweep before its cluster starts rather than failing every run."""
        for changes in self.overrides():
            try:
                configured(Run("", "", self.config, changes))
            except ValueError as error:
                raise ValueError(f"{where}: {error}") from None


def load_spec(path) -> SweepSpec:
    """The ``SweepSpec`` of a YAML file, with relative paths made relative to its folder. Raises ValueError naming
    the file and each wrong field."""
    path = Path(path)
    document = read_yaml(path)
    if not isinstance(document, dict):
        raise ValueError(f"{path}: a sweep spec is a mapping with recordings, config, set, vary, runs")
    try:
        spec = SweepSpec.model_validate(document)
    except ValidationError as error:
        problems = "; ".join(f"{'.'.join(map(str, e['loc'])) or 'spec'}: {e['msg']}" for e in error.errors())
        raise ValueError(f"{path}: {problems}") from None
    folder = path.resolve().parent
    for source in spec.recordings:
        if isinstance(source, FileSource):
            source.file = str(folder / source.file)
        elif isinstance(source, GlobSource):
            source.glob = str(folder / source.glob)
    if spec.config is not None:
        spec.config = str(folder / spec.config)
    return spec
