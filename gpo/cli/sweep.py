"""``python -m gpo sweep``: many runs (recordings x configs) on a Dask cluster, resumable (``gpo.batch``)."""

from __future__ import annotations

from pathlib import Path

from gpo.batch.cluster import add_cluster_arguments
from gpo.io.outputs import check_output_folder
from gpo.pipeline.config import load_config

NAME = "sweep"
HELP = "many runs (recordings x configs) on a Dask cluster, resumable"


def add_arguments(parser) -> None:
    parser.add_argument("spec", type=Path, help="the sweep's YAML: recordings, config, set, vary, runs")
    parser.add_argument("--out", type=Path, required=True, help="results folder (a sweep resumes in it)")
    add_cluster_arguments(parser)


def run(args) -> int:
    """Everything checked (the spec, its configs, the presets, ``--out``, ``--workers``, the scheduler's address)
    before the cluster starts; the spec's presets rendered on the cluster (cached), then every run; the summary."""
    from gpo.batch.cluster import cluster_client
    from gpo.batch.spec import load_spec
    from gpo.batch.sweep import sweep
    from gpo.batch.table import summary_text
    from gpo.sim.population import render
    from gpo.sim.record import preset

    spec = load_spec(args.spec)
    check_output_folder(args.out, [args.spec, spec.config], "--out")
    load_config(spec.config)  # a base config that cannot be read stops the sweep before it starts
    spec.check_configs(args.spec)
    for name, _ in spec.presets():
        preset(name)
    if args.workers is not None and args.workers < 1:
        raise ValueError(f"--workers must be at least 1, not {args.workers}")
    with cluster_client(args.scheduler, args.workers) as client:
        bags = render(client, spec.presets())
        result = sweep(spec.expand({pair: str(path) for pair, path in bags.items()}), args.out, client)
    print(summary_text(result.table))
    failed = result.failed
    print(
        f"{len(result.executed)} runs done now, {len(result.reused)} already done before, {len(failed)} failed; "
        f"table: {args.out / 'results.parquet'} and results.csv"
    )
    return 1 if len(failed) else 0
