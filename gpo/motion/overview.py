"""The floor's motion read on the whole of a wider view: a check of the KLT flow that reflections cannot fool.

On a glossy floor whose own grain is faint, the mirrored lamps are most of what the Lucas-Kanade windows see: their
edges pull every track, the reflection layer moves at a few hundredths of the floor's speed (``gpo.motion.layers``),
and the flow can lock onto it from the first frames with no check of ``gpo.motion.klt`` failing. Phase correlation
over a whole view weighs every spatial frequency alike (the cross-power spectrum is whitened), so the floor's fine
grain outweighs the lamps' blurred reflections; over a view ``scale`` times wider and longer than the floor image
(``gpo.floor_image.image.FloorImage.widened``, the same pixel count) the floor's shift stays inside the view.

``Overview.observe`` gives the shift between two consecutive views in the floor image's pixels; ``replaces_median``
tells when it replaces the flow's median, the correlation's peak being clear: the flow was flagged; or its median
shows what reflections do to it (``pulled_short``: it lies along the overview's shift, within ``tolerance_px`` of
its line, and falls short of it by more than that, the shift being at least twice that long); or the two disagree
by more than ``tolerance_px`` and the shift lies nearer the motion predicted from the previous frame than the median
does. ``gpo.motion.klt.FloorFlow`` then measures the frame's motion as the overview's translation at the floor
image's middle (``FlowQuality.overview``). On a matte floor the two agree to a fraction of a pixel and nothing
changes. Where something else moves through the view (a sheet dragged across the floor) the whole view follows it as
readily as the floor, away from the robot's steady motion, and the tracks' median, which the mover's few tracks do
not move, is kept: the sample paths' Test1 with its dragged sheets ends 0.21 % off, as with no check (accepting every
disagreement made it 12.5 %). On a glossy floor during spins the reflections' pull is not along the shift's line;
there the prediction tells the floor's shift from a locked median (population draw 16: 57 % with the line alone,
17.7 % with the prediction, 5.2 % accepting every disagreement).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class OverviewShift:
    """How far the floor moved between two views (``shift_px``, (2,) in the floor image's pixels, u right, v down)
    and how clear the correlation's peak was (``peak``, 0-1: the share of the whitened correlation in it)."""

    shift_px: np.ndarray
    peak: float


class Overview:
    """Phase correlation between views of ``size`` (width, height) pixels, each ``scale`` times the floor image's
    pixel: of two views (``shift``), or of each view with the one before it (``observe``)."""

    def __init__(self, scale: float, size: tuple[int, int]):
        self.scale = float(scale)
        self._window = cv2.createHanningWindow(size, cv2.CV_32F)
        self._previous: np.ndarray | None = None

    def observe(self, view: np.ndarray) -> OverviewShift | None:
        """The floor's shift from the previous view to ``view`` (float32, (height, width)), or None for the first."""
        previous, self._previous = self._previous, view
        return None if previous is None else self.shift(previous, view)

    def shift(self, previous: np.ndarray, view: np.ndarray) -> OverviewShift:
        """The floor's shift from the view ``previous`` to ``view`` (float32, (height, width) each).

        The whole views are correlated, reflections and all: taking out what stands still (a running mean of the
        views) removes the reflections' own correlation peak near no motion, but at a slow crawl it removes much of
        the floor too, and on the simulated matte floors it then disagreed with right tracks (the sample's final
        error 0.023 % became 0.110 %)."""
        (du, dv), peak = cv2.phaseCorrelate(previous, view, self._window)
        return OverviewShift(self.scale * np.array([du, dv]), float(peak))


PROBE_FRAMES = 4  # at rest the whole view is correlated every this many frames ...
ALERT_FRAMES = 30  # ... and in every frame for this many after it last changed a frame's motion or its doubt


class Schedule:
    """When the whole-view check runs: in every frame that needs it, and between those only now and then.

    On a matte floor the check confirms the tracks and changes nothing; its correlation and the wider view it reads
    are most of what a frame costs beyond reading it, remapping it and following its tracks. So it runs in a frame
    that shows a reason for it (``due(needed)``: the flow flagged, the check wary, or the tracks in two layers,
    ``gpo.motion.layers.layered``), in every frame for ``ALERT_FRAMES`` after it last changed a frame's motion or
    put it in doubt (``alert``: a glossy floor's reflections keep it busy), and at rest every ``PROBE_FRAMES``-th
    frame, so that reflections the tracks have locked onto unseen are found within that many frames. A new stream
    starts alert, so that tracks locked onto reflections from the first frame are caught."""

    def __init__(self):
        self._since = 0  # frames since the check last ran
        self._alert = ALERT_FRAMES  # frames it still runs in whatever they show

    def due(self, needed: bool) -> bool:
        """Whether the check runs in the next frame, ``needed`` saying whether the frame shows a reason for it."""
        self._since += 1
        self._alert = max(self._alert - 1, 0)
        if not (needed or self._alert or self._since >= PROBE_FRAMES):
            return False
        self._since = 0
        return True

    def alert(self) -> None:
        """The check changed a frame's motion or put it in doubt: it runs in every frame for a while."""
        self._alert = ALERT_FRAMES


def pulled_short(median: np.ndarray, shift_px: np.ndarray, tolerance_px: float) -> bool:
    """Whether the flow's ``median`` (floor-image pixels) shows a slower layer's pull on it: within ``tolerance_px``
    of the overview's ``shift_px`` line, more than ``tolerance_px`` short of the shift along it, the shift at least
    ``2 * tolerance_px`` long (a shorter one cannot tell the pull from a crawl)."""
    length = float(np.hypot(*shift_px))
    if length < 2.0 * tolerance_px:
        return False
    along = shift_px / length
    beside = abs(float(median[0] * along[1] - median[1] * along[0]))
    return float(median @ along) < length - tolerance_px and beside <= tolerance_px


def disagrees(median: np.ndarray, overview: OverviewShift, tolerance_px: float, min_peak: float) -> bool:
    """Whether the overview's shift, its correlation's peak reaching ``min_peak``, lies more than ``tolerance_px``
    from the flow's ``median`` (floor-image pixels): one of the two misreads the floor, and the frame's motion is in
    doubt whichever measures it."""
    return overview.peak >= min_peak and float(np.hypot(*(median - overview.shift_px))) > tolerance_px


def replaces_median(
    median: np.ndarray | None,
    flag: str | None,
    overview: OverviewShift,
    predicted: np.ndarray,
    tolerance_px: float,
    min_peak: float,
    wary_px: float | None = None,
) -> bool:
    """Whether the overview's shift should replace the flow's ``median`` (floor-image pixels; ``flag`` when the flow
    was flagged): the overview's peak reaches ``min_peak``, and the flow was flagged, or the two lie more than
    ``tolerance_px`` apart and the median was ``pulled_short`` or the shift lies nearer the motion ``predicted`` from
    the previous frame (pixels) than the median does. ``wary_px`` (after a frame in doubt,
    ``gpo.motion.klt.KLTParameters.overview_wary_share``): the two disagree beyond this instead of ``tolerance_px``;
    the pull's own test keeps ``tolerance_px``, so that on a smaller disagreement the prediction decides, which tells
    a whole view dragged along by something moving through it (away from the steady motion) from a median pulled
    short by reflections."""
    if overview.peak < min_peak:
        return False
    if flag is not None:
        return True
    if not disagrees(median, overview, tolerance_px if wary_px is None else wary_px, min_peak):
        return False
    shift = overview.shift_px
    nearer = float(np.hypot(*(shift - predicted))) < float(np.hypot(*(median - predicted)))
    return pulled_short(median, shift, tolerance_px) or nearer
