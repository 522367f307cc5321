"""How long each chapter's ipywidgets panel takes to update after one control change, in seconds.

    python benchmarks/widget_panels.py [--chapters 05 07_ekf_fusion ...] [--timeout SECONDS]
                                       [--write benchmarks/results/widget_panels.json]

Each chapter (default: every notebooks/*.ipynb; ``--chapters`` takes names or their leading part, e.g. ``07`` or
``01``) is executed with nbclient in a python3 kernel working in notebooks/, as CI runs it; the files on disk stay
as they are. One extra cell, appended to the notebook in memory, looks in IPython's output cache ``Out`` for the
panels the chapter showed (the ``VBox`` a ``gpo.book`` panel returns as a cell's result) and times one update of
each: its first slider (else its first dropdown or toggle buttons) set to a neighbouring allowed value (one step up,
or down at the top of the range; the next option of a choice). The change runs the panel's redraw in the kernel
(``ipywidgets.interactive_output``), the inline backend's PNG of the figure included; the best of three changes,
back and forth between the two values, counts. The cell prints one JSON line per panel; this script gathers them
into a table. Target: every panel under 1 s per update at the chapter's settings on a 2-core machine; slower
panels are flagged. ``--write`` keeps the rows as JSON (``benchmarks/results/widget_panels.json``).

Like CI (.ci/run), the chapters get ``GPO_DATA_DIR=../shared/real_data`` when that folder exists and the variable
is unset (chapter 09 reads it, and the Table 4 results ``python -m gpo table4`` caches). A simulated recording a
chapter needs is rendered on first use (minutes each) and cached.
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path
from queue import Empty

import nbformat
from nbclient import NotebookClient
from nbclient.exceptions import CellExecutionError, CellTimeoutError, DeadKernelError

from gpo.io.outputs import write_json

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = ROOT / "notebooks"
TARGET_S = 1.0
POLL_S = 1.0  # the longest single wait for a kernel message

TIMING_CELL = """
import json as _json
import math as _math
import time as _time

import ipywidgets as _widgets
import matplotlib.pyplot as _plt

_SLIDERS = (_widgets.FloatSlider, _widgets.FloatLogSlider, _widgets.IntSlider)
_CHOICES = (_widgets.Dropdown, _widgets.ToggleButtons)


def _descendants(widget):
    yield widget
    for child in getattr(widget, "children", ()):
        yield from _descendants(child)


def _redraw(control):
    # the function ipywidgets.interactive_output calls when the control changes (its observer's closure holds it)
    for handler in control._trait_notifiers.get("value", {}).get("change", []):
        code = getattr(handler, "__code__", None)
        if code is not None and handler.__name__ == "observer" and "f" in code.co_freevars:
            return handler.__closure__[code.co_freevars.index("f")].cell_contents
    return None


def _neighbour(control):
    # (attribute, value now, a neighbouring allowed value)
    if isinstance(control, _CHOICES):
        now = control.index  # None: nothing chosen
        return "index", now, 0 if now is None else (now + 1) % len(control.options)
    if isinstance(control, _widgets.FloatLogSlider):
        exponent = _math.log(control.value, control.base)
        step = control.step if exponent + control.step <= control.max else -control.step
        return "value", control.value, control.base ** (exponent + step)
    step = control.step if control.value + control.step <= control.max else -control.step
    return "value", control.value, control.value + step


def _shown(control, attribute, value):
    if attribute == "value":
        return f"{value:.6g}"
    option = None if value is None else control.options[value]
    return str(option[0] if isinstance(option, tuple) else option)  # a (label, value) option by its label


def _time_panel(cell, panel):
    controls = [widget for widget in _descendants(panel) if _redraw(widget) is not None]
    if not controls:  # no interactive_output: whatever observes the panel's sliders and choices
        controls = [widget for widget in _descendants(panel) if isinstance(widget, _SLIDERS + _CHOICES)]
    sliders = [c for c in controls if isinstance(c, _SLIDERS)]
    choices = [c for c in controls if isinstance(c, _CHOICES)]
    if not sliders + choices:
        return None
    control = (sliders + choices)[0]
    redraw = _redraw(control)
    name = "panel of " + ", ".join(c.description for c in controls) if redraw is None else redraw.__qualname__
    attribute, now, other = _neighbour(control)
    seconds = []
    for value in (other, now, other):  # the best of three, back and forth
        started = _time.perf_counter()
        setattr(control, attribute, value)
        seconds.append(_time.perf_counter() - started)
        _plt.close("all")
    return {
        "chapter": _CHAPTER,
        "cell": cell,
        "panel": name.split(".<locals>")[0],  # the panel function whose redraw this is
        "controls": [c.description for c in controls],
        "control": control.description,
        "change": f"{_shown(control, attribute, now)} -> {_shown(control, attribute, other)}",
        "seconds": round(min(seconds), 4),
        "all_seconds": [round(s, 4) for s in seconds],
    }


_timed = set()
for _cell, _result in sorted(Out.items()):
    if isinstance(_result, _widgets.VBox) and id(_result) not in _timed:
        _timed.add(id(_result))
        _row = _time_panel(_cell, _result)
        if _row is not None:
            print(_json.dumps(_row), flush=True)
"""


def chapter_paths(names: list[str] | None) -> list[Path]:
    paths = sorted(NOTEBOOKS.glob("*.ipynb"))
    if not names:
        return paths
    chosen = []
    for name in names:
        matching = [path for path in paths if path.stem.startswith(name)]
        if not matching:
            sys.exit(f"no chapter matches {name!r}; the chapters: {', '.join(path.stem for path in paths)}")
        chosen += [path for path in matching if path not in chosen]
    return chosen


def poll_in_slices(channel) -> None:
    """Make the kernel channel's ``get_msg`` wait in polls of at most ``POLL_S`` seconds. Now and then a message from
    the kernel (ipykernel 7) wakes no poll and is found only when the poll times out; nbclient waits for a cell's reply
    in one poll as long as the cell's timeout, so a cell of one second could otherwise take the whole timeout."""
    get_msg = channel.get_msg

    async def sliced(timeout: float | None = None) -> dict:
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            left = POLL_S if deadline is None else max(0.0, deadline - time.monotonic())
            try:
                return await get_msg(timeout=min(POLL_S, left))
            except Empty:
                if deadline is not None and left <= POLL_S:
                    raise

    channel.get_msg = sliced


def time_chapter(path: Path, timeout_s: float) -> list[dict]:
    """Execute the chapter with the timing cell appended (in memory) and return the rows the cell printed."""
    notebook = nbformat.read(path, as_version=4)
    notebook.cells.append(nbformat.v4.new_code_cell(f"_CHAPTER = {path.stem!r}\n{TIMING_CELL}"))

    def patient(notebook) -> None:  # nbclient's hook once the kernel client is up
        poll_in_slices(client.kc.shell_channel)
        poll_in_slices(client.kc.iopub_channel)

    client = NotebookClient(
        notebook,
        timeout=timeout_s,
        kernel_name="python3",
        resources={"metadata": {"path": str(path.parent)}},
        on_notebook_start=patient,
    )
    client.execute()
    lines = [
        line
        for output in notebook.cells[-1].outputs
        if output.output_type == "stream" and output.name == "stdout"
        for line in output.text.splitlines()
    ]
    return [json.loads(line) for line in lines if line.startswith("{")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--chapters", nargs="+", help="notebook names, or their leading part (default: all)")
    parser.add_argument("--timeout", type=float, default=1800.0, help="seconds allowed per cell")
    parser.add_argument("--write", type=Path, help="JSON file for the results")
    args = parser.parse_args()
    real_data = ROOT.parent / "shared" / "real_data"
    if "GPO_DATA_DIR" not in os.environ and real_data.is_dir():
        os.environ["GPO_DATA_DIR"] = str(real_data)

    rows, failed = [], []
    for path in chapter_paths(args.chapters):
        started = time.perf_counter()
        try:
            found = time_chapter(path, args.timeout)
        except (CellExecutionError, CellTimeoutError, DeadKernelError) as error:
            failed.append(path.stem)
            print(f"{path.stem}: FAILED\n{str(error)[-2000:]}", flush=True)
            continue
        rows += found
        print(f"{path.stem}: executed in {time.perf_counter() - started:.0f} s, {len(found)} panel(s)", flush=True)
        for row in found:
            print(json.dumps(row), flush=True)

    print()
    print(f"{'chapter':<22}{'cell':>5}  {'panel':<22}{'control':<28}{'change':<24}{'seconds':>8}")
    for row in rows:
        verdict = "ok" if row["seconds"] < TARGET_S else f"SLOW (>= {TARGET_S:.1f} s)"
        print(
            f"{row['chapter']:<22}{row['cell']:>5}  {row['panel']:<22}{row['control']:<28}{row['change']:<24}"
            f"{row['seconds']:8.2f}  {verdict}"
        )
    slow = [row for row in rows if row["seconds"] >= TARGET_S]
    print(f"{len(rows)} panel(s), {len(slow)} at or above {TARGET_S:.1f} s")
    if failed:
        print(f"chapters that failed to run: {', '.join(failed)}")
    if args.write:
        print(f"wrote {write_json(args.write, rows)}")
    if failed:
        sys.exit(1)


if __name__ == "__main__":
    main()
