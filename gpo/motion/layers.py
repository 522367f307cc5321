"""The floor's own tracks told from a glossy floor's reflections: two layers of motion in one floor image.

On a glossy floor the reflection of the ceiling's lights lies as deep below the floor as the lights are above it, so
as the camera (at height h) drives, the reflection of lights at height H moves through the floor image at
h / (h + H) of the floor's speed, a few hundredths. On a screed whose own grain is fainter than those reflections
they are much of the texture the corners find; they pull the median short and no check of ``gpo.motion.klt``
fails. ``slower_count`` counts such a slower layer among a frame's vectors (``FlowQuality.slower``);
``floor_layer`` tells the floor's own tracks from the reflections' by the geometry of the two layers, for the
estimators that want the floor alone (``gpo-exact``), where ``layered`` says the tracks may hold two layers
(``FlowQuality.layers``). Pixels (u, v) of the floor image: u right, v down.
"""

from __future__ import annotations

import cv2
import numpy as np

from gpo.motion.median import median_of

SLOWER_SPEED = 0.5  # a kept vector moving along the median at under this share of its length is in a slower layer


SLOWER_MIN_PX = 2.0  # ... looked for once the median is this long (on a robot standing still nothing is slower)


SLOWER_LAYER_SHARE = 0.1  # a frame with at least this share of its kept vectors in a slower layer holds one


LAYER_RADIUS_PX = 1.0  # the tracks of one layer move alike to this, once the frame's rotation is taken out


LAYER_MIN_TRACKS = 6  # ... and a layer holds at least this many of them


MIRROR_SHARE = (0.01, 0.3)  # a reflection moves h / (h + H) of the floor: a camera 0.08-0.3 m up, lights 1-10 m


def slower_layer(slower: int, kept: int) -> bool:
    """Whether ``slower`` of ``kept`` vectors make a slower layer (at least ``SLOWER_LAYER_SHARE`` of them)."""
    return kept > 0 and slower >= SLOWER_LAYER_SHARE * kept


def slower_count(vectors: np.ndarray, median: np.ndarray) -> int:
    """How many ``vectors`` (N, 2) move along ``median`` (2,) at under ``SLOWER_SPEED`` of its length (0 while
    it is shorter than ``SLOWER_MIN_PX``)."""
    length = float(np.hypot(*median))
    if length < SLOWER_MIN_PX:
        return 0
    return int(np.count_nonzero(vectors @ median < SLOWER_SPEED * length**2))


def layered(vectors: np.ndarray) -> bool:
    """Whether the tracks' ``vectors`` (N, 2) may move in two layers: at least ``LAYER_MIN_TRACKS`` of them move along
    their median vector by more than half its length more or less than it. A single rigid layer moves every track
    alike but for its turn; a reflection's tracks move a few hundredths of the floor's, and whichever layer holds the
    median, the other's tracks differ from it by more than that (on the simulated glossy floor each frame
    ``floor_layer`` split had at least 29 such tracks, on the matte sample 2 frames of 440 had 6 or more). A turn
    since the keyframe makes a single layer look layered too, which costs only time. The gate before
    ``floor_layer`` and the whole-view check (``gpo.motion.overview.Schedule``), not a split."""
    if len(vectors) < 2 * LAYER_MIN_TRACKS:
        return False
    median = median_of(vectors, axis=0)
    length = float(np.hypot(*median))
    along = vectors @ median / max(length, 1e-9)
    return int(np.count_nonzero(np.abs(along - length) > 0.5 * length)) >= LAYER_MIN_TRACKS


def floor_layer(start: np.ndarray, end: np.ndarray, nadir: np.ndarray) -> np.ndarray:
    """Which tracks from ``start`` to ``end`` ((N, 2) floor-image pixels) follow the floor itself rather than a
    reflection in it, given ``nadir`` (2,), the floor-image pixel straight below the camera: a mask (N,).

    A light at height H above a glossy floor is mirrored H below it; a camera at height h sees the mirror image on
    the floor image at the nadir plus h / (h + H) of the offset it would have there were it on the floor. So as the
    robot moves, every floor point turns about the nadir by the frame's rotation and then moves by the nadir's
    displacement d, and every reflection turns alike and moves by h / (h + H) d: a few hundredths of d, along it.
    The rotation is the layers' common one (a RANSAC fit of a rotation, translation and scale to all tracks,
    whichever layer it settles on); taken out, it leaves each track's displacement, and the floor is the group of
    at least ``LAYER_MIN_TRACKS`` tracks within ``LAYER_RADIUS_PX`` of one another, the farthest-moving (at least
    ``SLOWER_MIN_PX``) with reflections: as many tracks again about the line from it to the nadir, their median at
    ``MIRROR_SHARE`` of its displacement, and the median of all tracks on that line too (a blend of the two layers).
    A thing moving over the floor (a sheet dragged across it) moves another way than the floor's tracks and their
    median. Every track when no group qualifies (no reflections, too few tracks, no fit).
    """
    everything = np.ones(len(start), bool)
    if len(start) < 2 * LAYER_MIN_TRACKS:
        return everything
    fit, _ = cv2.estimateAffinePartial2D(start, end, method=cv2.RANSAC, ransacReprojThreshold=LAYER_RADIUS_PX)
    if fit is None:
        return everything
    rotation = fit[:, :2] / np.hypot(fit[0, 0], fit[1, 0])  # the fit is scale times rotation
    moved = end - nadir - (start - nadir) @ rotation.T  # each track's displacement once the rotation is out
    lengths = _lengths(moved)
    # a reflection's track moves under half its layer's vector (|moved|^2 < (0.5 L)^2 + r^2), and a layer's vector L
    # is a median of tracks, no longer than the longest components' hypotenuse: too few such short tracks, no layers
    reach = np.hypot(*np.abs(moved).max(axis=0))
    if np.count_nonzero(lengths**2 < (1 + 1e-9) * (0.25 * reach**2 + LAYER_RADIUS_PX**2)) < LAYER_MIN_TRACKS:
        return everything
    blend = median_of(moved, axis=0)
    near = _lengths(moved[:, None] - moved[None]) < LAYER_RADIUS_PX
    neighbours = near.sum(axis=1)
    tried = set()  # the groups already judged: on a tight floor most tracks have the very same neighbours
    for seed in np.argsort(-lengths):  # the farthest-moving tracks first
        if neighbours[seed] < LAYER_MIN_TRACKS:
            continue
        group = np.packbits(near[seed]).tobytes()
        if group in tried:
            continue
        tried.add(group)
        centre = median_of(moved[near[seed]], axis=0)
        length = float(np.hypot(*centre))
        if length < SLOWER_MIN_PX:
            break
        normal = np.array([-centre[1], centre[0]]) / length
        if abs(blend @ normal) > LAYER_RADIUS_PX * (0.3 + 0.25 * np.hypot(*blend)) or blend @ centre < 0:
            continue  # the tracks' median is not on this group's line: not the floor's layers
        along = moved @ centre / length**2  # each track's displacement along the group's, in units of it
        mirrored = (along > -0.1) & (along < 0.5) & (np.abs(moved @ normal) < LAYER_RADIUS_PX)
        if mirrored.sum() >= LAYER_MIN_TRACKS and MIRROR_SHARE[0] <= median_of(along[mirrored]) <= MIRROR_SHARE[1]:
            return _lengths(moved - centre) < LAYER_RADIUS_PX
    return everything


def _lengths(vectors: np.ndarray) -> np.ndarray:
    """The lengths of ``vectors`` (..., 2), the sum of squares as ``np.linalg.norm`` forms it (a reduction over an axis
    of two is several times slower than the two terms)."""
    return np.sqrt(vectors[..., 0] * vectors[..., 0] + vectors[..., 1] * vectors[..., 1])
