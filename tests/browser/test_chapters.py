"""Every chapter's widget panels as a reader meets them, in JupyterLab in Chromium: the panels' cells and the cells
they need (``needed_cells.cells_panels_need``) run without an error, and one control of a panel, moved, changes what the
panel shows. A screenshot of each panel goes to ``out/screenshots/``.

nbval runs every cell of every chapter; only a browser shows that a panel is drawn and redrawn when a control moves.

The chapters are read one after the other in one page (``Reader``), each opened as the file browser opens a notebook
and closed when its test ends: starting JupyterLab in a page costs Chromium about 4 s of processor time, opening a
chapter in a running one about 2 s.
"""

from __future__ import annotations

import base64
import hashlib
import io
import re
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pytest
from needed_cells import cells_panels_need
from PIL import Image

ROOT = Path(__file__).resolve().parents[2]
SCREENSHOTS = ROOT / "out" / "screenshots"
RUN_S = 300.0  # the cells of the slowest chapter's panels run in about half a minute on two cores
UPDATE_S = 60.0
KERNEL_START_S = 60.0
SETTLE_S = 1.0  # an output unchanged this long, its kernel idle, is complete
POLL_MS = 200  # how often the page and the server are asked again
VIEWPORT = {"width": 1400, "height": 1000}
ERROR_MARKS = ("Traceback (most recent call last)", "Error displaying widget")


class Move(NamedTuple):
    """The control labelled ``label`` set to ``value`` (a slider's typed value, or the option chosen)."""

    label: str
    value: str


MOVES = {
    "00_overview": Move("t [s]", "2.00"),
    "01_eucm_calibration": Move("model", "pinhole"),
    "01_eucm_model": Move("alpha", "0.50"),
    "02_cubemap": Move("face [px]", "300"),
    "03_ground_plane_image": Move("ahead [m]", "0.40"),
    "04_ortho_gpi": Move("half width [m]", "0.08"),
    "05_klt_flow": Move("window [px]", "15"),
    "06_kinematics": Move("delta [deg]", "30.00"),
    "07_ekf_fusion": Move("floor sigma v [m/s]", "0.01"),
    "08_floor_features": Move("ratio test", "1.00"),  # t at 0.90 keeps every loop of its pair: only timings changed
    "09_evaluation": Move("alignment", "se2"),
}


WITHOUT_PANEL = {  # chapters of commands and their outputs, and the lab's chapters of saved results: no panel to move
    "10_your_robot",
    "A_glossy_floors",
    "B_population",
    "C_second_paper",
    "D_many_recordings",
    "E_precision",
    "F_fusion_in_depth",
}


def test_every_chapter_has_a_move():
    assert sorted([*MOVES, *WITHOUT_PANEL]) == sorted(path.stem for path in (ROOT / "notebooks").glob("*.ipynb"))


def _menu(page, menu: str, item: str) -> None:
    page.locator(".lm-MenuBar-itemLabel", has_text=re.compile(f"^{re.escape(menu)}$")).click()
    page.locator(".lm-Menu-itemLabel", has_text=re.compile(f"^{re.escape(item)}$")).click()


def _prompts(page) -> list[str]:
    return page.locator(".jp-Notebook .jp-CodeCell .jp-InputPrompt").all_inner_texts()


def _errors(page) -> list[str]:
    texts = page.locator(".jp-Notebook .jp-OutputArea-output").all_inner_texts()
    return [text for text in texts if any(mark in text for mark in ERROR_MARKS)]


def _kernel_idle(lab, path: str) -> bool:
    """Whether the kernel of notebook ``path`` has started and is idle, as the server sees it."""
    sessions = lab.request("GET", "/api/sessions")
    return any(session["path"] == path and session["kernel"]["execution_state"] == "idle" for session in sessions)


def _settled(page, lab, path: str, output) -> str:
    """``_shown(output)`` once the kernel is idle and the output has not changed for ``SETTLE_S``."""
    deadline = time.monotonic() + UPDATE_S
    shown, since = _shown(output), time.monotonic()
    while time.monotonic() < deadline:
        page.wait_for_timeout(POLL_MS)
        now = _shown(output)
        if now != shown:
            shown, since = now, time.monotonic()
        elif time.monotonic() - since >= SETTLE_S and _kernel_idle(lab, path):
            return shown
    pytest.fail(f"the panel was still changing, or its kernel busy, after {UPDATE_S:.0f} s")


def _wait_for_kernel(page, lab, path: str) -> None:
    """Wait until the chapter's kernel has started and is idle, choosing the chapter's own kernel if asked."""
    deadline = time.monotonic() + KERNEL_START_S
    while time.monotonic() < deadline:
        dialog = page.locator(".jp-Dialog", has_text="Select Kernel")
        if dialog.is_visible():
            dialog.locator(".jp-Dialog-button.jp-mod-accept").click()
        if _kernel_idle(lab, path):
            return
        page.wait_for_timeout(POLL_MS)
    pytest.fail(f"no idle kernel for {path} after {KERNEL_START_S:.0f} s")


def _run(page, indices: list[int]) -> None:
    """Clear every output (and execution count), run the code cells ``indices`` in order, and wait until none is
    queued or running and each has run, or an error stopped the run."""
    _menu(page, "Edit", "Clear Outputs of All Cells")
    cells = page.locator(".jp-Notebook .jp-CodeCell")
    for index in indices:
        cells.nth(index).locator(".jp-InputPrompt").click()
        page.keyboard.press("Control+Enter")
    deadline = time.monotonic() + RUN_S
    while time.monotonic() < deadline:
        prompts = _prompts(page)
        busy = any("*" in prompt for prompt in prompts)
        if not busy and (all(re.search(r"\[\d+\]", prompts[index]) for index in indices) or _errors(page)):
            return
        page.wait_for_timeout(POLL_MS)
    pytest.fail(f"the cells were still running after {RUN_S:.0f} s: {_prompts(page)}")


def _description(page, label: str):
    """The description ``label`` of a control; the control is its parent."""
    return page.locator("label.widget-label", has_text=re.compile(f"^{re.escape(label)}$")).first


def _move(control, value: str) -> None:
    classes = control.get_attribute("class")
    if "widget-slider" in classes:
        readout = control.locator(".widget-readout")
        readout.click()
        readout.press("Control+A")
        readout.type(value)
        readout.press("Enter")
    elif "widget-dropdown" in classes:
        control.locator("select").select_option(label=value)
    elif "widget-toggle-buttons" in classes:
        control.locator(f"button[data-value='{value}']").click()
    else:
        raise AssertionError(f"no way to move a control of classes {classes!r}")


def _ink(output) -> float:
    """The share of the panel's figure that is not background (0 without a figure): a figure sent half drawn is
    mostly white."""
    sources = output.locator("img").evaluate_all("images => images.map(image => image.src)")
    if not sources:
        return 0.0
    png = base64.b64decode(sources[0].split(",", 1)[1])
    grey = np.asarray(Image.open(io.BytesIO(png)).convert("L"))
    return float(np.mean(grey < 250))


def _shown(output) -> str:
    """A digest of what a panel's output shows: its text and its images' data."""
    images = output.locator("img").evaluate_all("images => images.map(image => image.src)")
    return hashlib.sha256((output.inner_text() + "".join(images)).encode()).hexdigest()


def _screenshot(page, cell, path: Path) -> None:
    """A picture of the page with ``cell`` and its panel at the top."""
    cell.evaluate("cell => cell.scrollIntoView({block: 'start'})")
    cell.locator("img").evaluate_all("images => Promise.all(images.map(image => image.decode()))")
    page.wait_for_timeout(500)
    page.screenshot(path=path)


class Reader:
    """One JupyterLab page in which the chapters are opened one after the other: the first in a new page at its
    address, the next ones in the running JupyterLab (``docmanager:open``, the file browser's command), each closed,
    and its kernel stopped, when its test ends. A chapter whose test failed takes its page with it, so that the next
    chapter starts in a new one."""

    def __init__(self, browser, lab):
        self.browser, self.lab, self.page = browser, lab, None

    def open(self, path: str):
        """The page, showing the notebook ``path`` (relative to the project)."""
        if self.page is None:
            self.page = self.browser.new_page(viewport=VIEWPORT)
            self.page.goto(self.lab.address(path))
        else:
            self.page.evaluate("path => window.jupyterapp.commands.execute('docmanager:open', {path})", path)
        return self.page

    def close(self, failed: bool) -> None:
        """Close the open notebook (with the page, if its test ``failed``) and stop every kernel."""
        if self.page is not None and failed:
            self.page.close()
            self.page = None
        elif self.page is not None:
            self.page.evaluate(
                "() => { for (const widget of [...window.jupyterapp.shell.widgets('main')]) widget.dispose(); }"
            )
        self.lab.shut_down_kernels()


@pytest.fixture(scope="module")
def reader(lab, browser):
    opened = Reader(browser, lab)
    yield opened
    if opened.page is not None:
        opened.page.close()


@pytest.mark.parametrize("chapter", sorted(MOVES))
def test_chapter_runs_and_its_panel_redraws(lab, reader, chapter):
    path = f"notebooks/{chapter}.ipynb"
    notebook = ROOT / path
    saved = notebook.read_bytes()
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    (SCREENSHOTS / f"{chapter}-failed.png").unlink(missing_ok=True)
    failed = True
    try:
        page = reader.open(path)
        _wait_for_kernel(page, lab, path)
        _run(page, cells_panels_need(notebook))
        assert _errors(page) == []

        move = MOVES[chapter]
        description = _description(page, move.label)
        control = description.locator("xpath=..")
        cell = page.locator(".jp-Notebook .jp-CodeCell", has=description)
        output = cell.locator(".widget-output").first
        before = _settled(page, lab, path, output)
        ink = _ink(output)
        _move(control, move.value)
        deadline = time.monotonic() + UPDATE_S
        while _shown(output) == before and time.monotonic() < deadline:
            page.wait_for_timeout(POLL_MS)
        assert _settled(page, lab, path, output) != before, f"{move.label} set to {move.value}: the panel stayed"
        assert _ink(output) >= 0.5 * ink, f"{move.label} set to {move.value}: the figure came back half drawn"
        assert _errors(page) == []
        _screenshot(page, cell, SCREENSHOTS / f"{chapter}.png")
        failed = False
    except Exception:
        if reader.page is not None:
            reader.page.screenshot(path=SCREENSHOTS / f"{chapter}-failed.png", full_page=True)
        raise
    finally:
        reader.close(failed)
    assert notebook.read_bytes() == saved, "the chapter on disk was rewritten"
