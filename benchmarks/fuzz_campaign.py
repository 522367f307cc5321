"""A long fuzzing campaign over gpo's readers: many mutated bags, configs, calibrations, sweep specs and TUM files.

    python benchmarks/fuzz_campaign.py [--examples N] [--seed S [S ...]] [--target NAME ...] [--out DIR]
    python benchmarks/fuzz_campaign.py --replay DIR/TARGET/NUMBER

Runs the strategies of tests/fuzzing (the ones tests/test_fuzz.py draws a few of in CI) with ``N`` inputs per reader
and command and per seed (default 800, over 10 000 in all), hypothesis seeded by each ``S`` in turn, and every input
through ``fuzzing.examine``. Prints, per reader, the inputs tried over every seed, how many were read whole and how
many refused (in part), its findings by kind, the slowest read, and every finding (a traceback, a hang over
``HANG_S`` s of processor time, a changed input, a wrong result, an error that names no file) once per kind and
place; then the totals. What goes wrong in the harness itself on an input is a finding too (a traceback), never
the campaign's end. Each finding's input is written to ``DIR/TARGET/NUMBER`` with what was done to its seed
(``how.txt``), and ``--replay`` reads it again and prints what happens. Exits 1 when a traceback, hang, changed
input or wrong result was found.
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
import time
import traceback
from collections import Counter
from pathlib import Path

from hypothesis import HealthCheck, Phase, given, seed, settings

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from fuzzing import HANG_S, KINDS, TARGETS, Finding, Mutant, Target, examine
from fuzzing.harness import refusals

FAILING = ("traceback", "hang", "changed input", "wrong result")
"""The kinds of finding that fail the property (an unclear error is counted, and fails only where promised)."""


def campaign(target: Target, examples: int, chosen_seed: int) -> tuple[Counter, list[Finding], float]:
    """``examples`` mutants through ``target``: (counts of outcomes, findings, slowest read in seconds)."""
    counts, findings, slowest = Counter(), [], [0.0]

    @seed(chosen_seed)
    @settings(
        max_examples=examples,
        database=None,
        deadline=None,
        phases=[Phase.generate],
        suppress_health_check=list(HealthCheck),
    )
    @given(target.mutants)
    def run(mutant: Mutant) -> None:
        started = time.perf_counter()
        try:
            result, finding = examine(target, mutant, unclear=True)
        except Exception as error:  # the harness itself failed on this input: a finding, and the campaign goes on
            detail = "in the harness: " + "".join(traceback.format_exception(error))
            result, finding = error, Finding(target.name, "traceback", detail, mutant)
        slowest[0] = max(slowest[0], time.perf_counter() - started)
        counts["tried"] += 1
        counts["refused" if refusals(result) else "read"] += 1
        if finding is not None:
            counts[finding.kind] += 1
            findings.append(finding)

    run()
    return counts, findings, slowest[0]


def signature(finding: Finding) -> str:
    """A finding's kind and place: its traceback's last line and frame, or its detail's first line; numbers and
    quoted text left out, so that findings alike count as one."""
    lines = [line for line in finding.detail.strip().splitlines() if line.strip()]
    place = next((line.strip() for line in reversed(lines) if line.strip().startswith("File ")), "")
    what = lines[-1] if finding.kind == "traceback" else lines[0]
    what = re.sub(r"'[^']*'|\"[^\"]*\"", "'…'", re.sub(r"0x[0-9a-f]+|[-+]?\d[\d.e+-]*", "#", what))
    return f"{finding.kind}: {what[:160]} {place}"


def keep(finding: Finding, out: Path, number: int) -> Path:
    """The finding's input written to ``out/TARGET/NUMBER``, with ``how.txt`` and ``finding.txt``."""
    folder = out / finding.target.replace(" ", "_") / str(number)
    folder.mkdir(parents=True, exist_ok=True)
    finding.mutant.write(folder)
    (folder / "how.txt").write_text(
        f"target: {finding.target}\nseed: {finding.mutant.seed}\nentry: {finding.mutant.entry}\n"
        + "".join(f"{step}\n" for step in finding.mutant.how)
    )
    (folder / "finding.txt").write_text(f"{finding.kind}\n{finding.detail}\n")
    return folder


def replay(folder: Path) -> int:
    """Read a kept input again with its target and print what happens."""
    how = dict(line.split(": ", 1) for line in (folder / "how.txt").read_text().splitlines()[:3])
    target = TARGETS[how["target"]]
    files = tuple(
        (str(p.relative_to(folder)), p.read_bytes())
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name not in ("how.txt", "finding.txt")
    )
    result, finding = examine(target, Mutant(how["seed"], files, how["entry"]), unclear=True)
    print(f"{target.name}: {type(result).__name__}: {str(result)[:2000]}")
    print("no finding" if finding is None else f"{finding.kind}:\n{finding.detail}")
    return 0 if finding is None or finding.kind not in FAILING else 1


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=800, help="inputs per reader and seed (default 800)")
    parser.add_argument(
        "--seed", type=int, nargs="+", default=[0], help="hypothesis's seeds, one after another (default 0)"
    )
    parser.add_argument("--target", action="append", choices=list(TARGETS), help="a reader (default: all)")
    parser.add_argument("--out", type=Path, help="where findings' inputs go (default: a new temporary folder)")
    parser.add_argument("--replay", type=Path, help="a kept input's folder: read it again")
    args = parser.parse_args()
    if args.replay:
        return replay(args.replay)
    out = args.out or Path(tempfile.mkdtemp(prefix="gpo-fuzz-campaign-"))
    seeds = ", ".join(map(str, args.seed))
    totals, started, failing = Counter(), time.perf_counter(), 0
    print(f"{args.examples} inputs per target and seed, seeds {seeds}; findings' inputs in {out}")
    for name in args.target or TARGETS:
        begun, counts, findings, slowest = time.perf_counter(), Counter(), [], 0.0
        for chosen_seed in args.seed:
            seed_counts, seed_findings, seed_slowest = campaign(TARGETS[name], args.examples, chosen_seed)
            counts.update(seed_counts)
            findings += seed_findings
            slowest = max(slowest, seed_slowest)
        totals.update(counts)
        kinds = ", ".join(f"{kind} {counts[kind]}" for kind in KINDS)
        print(
            f"\n{name}: {counts['tried']} inputs (seeds {seeds}), {counts['read']} read whole, {counts['refused']} "
            f"refused (in part or whole); findings {len(findings)}: {kinds}; slowest {slowest:.2f} s, "
            f"{time.perf_counter() - begun:.0f} s in all"
        )
        seen = {}
        for finding in findings:
            seen.setdefault(signature(finding), []).append(finding)
        if counts["unclear error"] and not TARGETS[name].names_file:
            totals["unclear, left to the caller"] += counts["unclear error"]
            print("  (this reader leaves naming the file to its caller: its unclear errors are counted apart)")
        for number, (place, alike) in enumerate(seen.items()):
            folder = keep(alike[0], out, number)
            failing += alike[0].kind in FAILING
            print(f"  {len(alike)} x {place}\n    reproduce: python benchmarks/fuzz_campaign.py --replay {folder}")
    unclear = totals["unclear error"] - totals["unclear, left to the caller"]
    print(
        f"\n{totals['tried']} inputs in {time.perf_counter() - started:.0f} s: "
        + ", ".join(f"{kind} {totals[kind]}" for kind in FAILING)
        + f", unclear error {unclear} (and {totals['unclear, left to the caller']} where the reader leaves naming"
        + f" the file to its caller); hangs are reads over {HANG_S:.0f} s of processor time"
    )
    return 1 if failing else 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        traceback.print_exc(limit=1)
        sys.exit(130)
