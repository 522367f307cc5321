"""Simulated recordings made on a Dask cluster: the presets a sweep names, each with the seeds it asks for.

``render(client, presets)`` renders (or finds in the cache, ``gpo.sim.record.recording``) every (preset, seed) pair
on the cluster's workers at once and returns their bags' paths. On a cluster of several machines the cache
(``GPO_CACHE_DIR``) must be a folder every worker and the client see under the same path.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from gpo.sim.record import preset, recording


def render(client, presets: Sequence[tuple[str, int | None]]) -> dict[tuple[str, int | None], Path]:
    """The bag of each (preset name, seed or None for the preset's own) in ``presets``, rendered on ``client``'s
    workers when not cached. Raises ValueError for an unknown preset before anything is rendered."""
    pairs = list(dict.fromkeys(presets))
    for name, _ in pairs:
        preset(name)
    if not pairs:
        return {}
    names, seeds = [name for name, _ in pairs], [seed for _, seed in pairs]
    formats, quiet = ["ros1"] * len(pairs), [False] * len(pairs)
    paths = client.gather(client.map(recording, names, formats, quiet, seeds, pure=False))
    return dict(zip(pairs, map(Path, paths), strict=True))
