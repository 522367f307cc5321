"""Render what a rig's camera sees of a textured floor in a walled room, with exact geometry.

Each pixel's ray comes from the camera model (``unproject``), is turned into ``base_link`` by
the mount and intersected with the floor z = 0. The robot moves in the plane, so the floor point
of every pixel is fixed in ``base_link``; a frame only turns and shifts those points by the
robot's pose (x, y, yaw) and looks them up in the floor texture. That lookup is anti-aliased by
trilinear mip-mapping: the level of each pixel follows from how far apart its neighbours' floor
points are (fixed per rig too). Rays that miss the floor hit the walls or the ceiling of a box
room around the floor.

Then the sensor: vignetting, exposure flicker, shot and read noise, optional motion blur
(several poses averaged over the exposure), and for a glossy floor a view-dependent sheen: the
reflection of the ceiling's lamps (``gpo.sim.ceiling``), which moves slower than the floor.

The disturbances of ``gpo.sim.disturbances`` are drawn too: a ``MovingSheet`` is part of the floor
lookup, anti-aliased alike; a ``Glint`` is added to the image where its floor point is seen.

Chessboards are drawn analytically with supersampling, so their corners are exact: lying on the
floor (``FloorBoard``) or held anywhere in front of the camera (``render_board_view``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np
import skimage.data
from scipy.spatial.transform import Rotation

from gpo.cameras import CameraModel
from gpo.cameras.rig import Rig, floor_points, rays_in_base
from gpo.cameras.targets import Chessboard, FloorBoard
from gpo.sim.ceiling import DEFAULT_CEILING, Ceiling, wrap
from gpo.sim.disturbances import SHEET_PAD, Glint, MovingSheet, print_sheet
from gpo.sim.floors import FloorTexture, mip_pyramid

BLACK, WHITE = 20.0, 220.0  # grey levels of a chessboard's black and white under the scene's light
CHUNK = 4096  # cv2.remap takes at most 32767 rows, so pixel lists are remapped as (n / CHUNK, CHUNK) maps


@dataclass(frozen=True)
class Sensor:
    """Photometric effects of the image sensor (grey levels of an 8-bit image)."""

    read_noise: float = 1.5  # standard deviation, grey levels
    shot_noise: float = 0.25  # standard deviation per sqrt(grey level)
    flicker: float = 0.03  # relative standard deviation of the per-frame exposure gain
    vignetting: float = 0.35  # relative darkening at 90 degrees off the optical axis


def camera_pose_in_world(rig: Rig, pose: np.ndarray) -> tuple[Rotation, np.ndarray]:
    """World <- optical rotation and optical centre (metres) for robot pose (x, y, yaw)."""
    x, y, yaw = pose
    base = Rotation.from_euler("z", yaw)
    return base * rig.mount.rotation, np.array([x, y, 0.0]) + base.apply(rig.mount.position)


@dataclass(frozen=True, eq=False)
class _PixelGroup:
    """The floor pixels whose lower mip level is ``level``: their flat image ``indices`` (N,), floor points
    ``points`` (N, 2) metres in base_link and their bounding box (x_min, y_min, x_max, y_max), the blend
    ``weight`` (N,) towards the next level (all zero, or all positive), and the points again as a float32
    (rows, CHUNK, 2) table (zero padded) that ``cv2.transform`` turns into the texture lookup map of a pose."""

    level: int
    indices: np.ndarray
    points: np.ndarray
    box: tuple[float, float, float, float]
    weight: np.ndarray
    table: np.ndarray


class FloorRenderer:
    """Renders ``rig``'s view of ``floor`` for robot poses; everything that does not move is precomputed.

    ``room_margin`` metres of floor surround the texture before the walls rise to the ``ceiling``
    (its height and lamps). The texture repeats mirrored beyond its edge, where it is far and small.
    ``sheets`` lie on the floor and move on their own; ``glints`` shine in the image (see ``Disturbances``).

    A frame costs one affine transform of each pixel group's floor-point table and two ``cv2.remap`` lookups
    (the group's mip level and the next), a walk of the rays that miss the floor to the room's walls, and the
    sensor's noise from OpenCV's generator seeded by the frame's seed; all in float32.
    """

    def __init__(
        self,
        rig: Rig,
        floor: FloorTexture,
        sensor: Sensor = Sensor(),
        room_margin=3.0,
        ceiling: Ceiling = DEFAULT_CEILING,
        *,
        sheets: tuple[MovingSheet, ...] = (),
        glints: tuple[Glint, ...] = (),
    ):
        self.rig, self.floor, self.sensor, self.ceiling = rig, floor, sensor, ceiling
        camera = rig.camera
        self._rays_base, valid = rays_in_base(rig, camera.pixel_grid())
        floor_xy, hits_floor = floor_points(rig, self._rays_base)
        hits_floor &= valid
        self.hits_floor, self.valid = hits_floor, valid
        self.floor_points = floor_xy  # (H, W, 2) metres in base_link, NaN where the ray misses the floor
        self._groups = self._group_by_level(floor_xy, self._mip_levels(floor_xy, hits_floor), hits_floor)
        x_min, x_max, y_min, y_max = floor.extent
        self._room = (
            x_min - room_margin, x_max + room_margin, y_min - room_margin, y_max + room_margin, ceiling.height_m
        )
        self._walls = cv2.pyrDown(cv2.pyrDown(skimage.data.brick())).astype(np.float32)
        self._off_floor = np.flatnonzero((valid & ~hits_floor).ravel())
        self._room_rays = np.ascontiguousarray(self._rays_base.reshape(-1, 3)[self._off_floor].T, np.float32)
        angle = np.arccos(np.clip(self._rays_base @ rig.mount.rotation.apply([0.0, 0.0, 1.0]), -1.0, 1.0))
        vignetting = np.where(valid, 1.0 - sensor.vignetting * (np.sin(np.minimum(angle, np.pi / 2)) ** 2), 0.0)
        self._vignetting = vignetting.astype(np.float32)
        self._ceiling = self._mirrored_ceiling() if floor.sheen else None
        self._sheets = tuple(
            (sheet, mip_pyramid(print_sheet(sheet.size_m, floor.texel, sheet.seed))) for sheet in sheets
        )
        self._glints = tuple(self._glint_patch(glint) for glint in glints)

    def _mip_levels(self, floor_xy: np.ndarray, hits_floor: np.ndarray) -> np.ndarray:
        """Fractional mip level per pixel: log2 of the larger step to a neighbour's floor point, in texels."""
        step_u = np.linalg.norm(np.gradient(floor_xy, axis=1), axis=-1)
        step_v = np.linalg.norm(np.gradient(floor_xy, axis=0), axis=-1)
        footprint = np.fmax(step_u, step_v)
        footprint = np.where(np.isfinite(footprint), footprint, 1e3)
        with np.errstate(divide="ignore"):
            level = np.log2(footprint / self.floor.texel)
        return np.where(hits_floor, np.clip(level, 0.0, len(self.floor.levels) - 1.0), np.nan)

    @staticmethod
    def _group_by_level(floor_xy, levels, hits_floor) -> list[_PixelGroup]:
        """Pixels grouped by their lower mip level, and within a level those that blend in the next level apart
        from those that do not (their footprint is below a texel, or the pyramid ends), which need one lookup."""
        flat = np.flatnonzero(hits_floor.ravel())
        lower = np.floor(levels.ravel()[flat]).astype(int)
        blends = levels.ravel()[flat] > lower
        groups = []
        for level, blend in sorted(set(zip(lower.tolist(), blends.tolist(), strict=True))):
            chosen = flat[(lower == level) & (blends == blend)]
            points = floor_xy.reshape(-1, 2)[chosen].astype(np.float64)
            table = np.zeros((-(-len(chosen) // CHUNK) * CHUNK, 2), np.float32)
            table[: len(chosen)] = points
            groups.append(
                _PixelGroup(
                    level=level,
                    indices=chosen,
                    points=points,
                    box=(*points.min(axis=0), *points.max(axis=0)),
                    weight=(levels.ravel()[chosen] - level).astype(np.float32),
                    table=table.reshape(-1, CHUNK, 2),
                )
            )
        return groups

    def _mirrored_ceiling(self) -> np.ndarray:
        """Where the mirror image of each floor pixel's ray meets the ceiling, (N, 2) metres in base_link."""
        rays = self._rays_base[self.hits_floor]
        reach = self._room[4] / -rays[:, 2]
        return (self.floor_points[self.hits_floor] + reach[:, None] * rays[:, :2]).astype(np.float32)

    def _glint_patch(self, glint: Glint) -> tuple[Glint, tuple[slice, slice], np.ndarray]:
        """The glint, the image window (rows, columns) it brightens and the grey levels it adds there."""
        reach = np.linalg.norm(self.floor_points - np.asarray(glint.centre_m), axis=-1) < 2.5 * glint.radius_m
        rows, cols = np.nonzero(reach)
        window = (slice(rows.min(), rows.max() + 1), slice(cols.min(), cols.max() + 1))
        added = np.where(self.hits_floor[window], glint.brightness(self.floor_points[window]), 0.0)
        return glint, window, added.astype(np.float32)

    def render(
        self, poses, frame_seed: int | tuple = 0, boards: tuple[FloorBoard, ...] = (), times_s=0.0
    ) -> np.ndarray:
        """The uint8 image for robot pose(s) (x, y, yaw) in metres and radians.

        ``poses`` (3,) or (K, 3): K poses are averaged (motion blur over the exposure).
        ``frame_seed`` seeds this frame's noise and flicker, so frames render alike in any order.
        ``times_s`` (scalar or (K,) seconds) is when each pose is seen: it says where the sheets are and
        how bright the glints shine.
        """
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        times = np.broadcast_to(np.asarray(times_s, dtype=float), len(poses))
        radiance = self._radiance(poses[0], times[0], boards)
        for pose, time in zip(poses[1:], times[1:], strict=True):
            radiance += self._radiance(pose, time, boards)
        radiance *= np.float32(1.0 / len(poses))
        for glint, window, added in self._glints:
            radiance[window] += np.float32(glint.gain(times.mean())) * added
        rng = np.random.default_rng(frame_seed)
        gain = 1.0 + self.sensor.flicker * rng.standard_normal()
        signal = radiance * self._vignetting
        signal *= np.float32(gain)
        deviation = np.maximum(signal, 0.0)
        deviation *= np.float32(self.sensor.shot_noise**2)
        deviation += np.float32(self.sensor.read_noise**2)
        noise = np.empty_like(signal)
        cv2.setRNGSeed(int(rng.integers(2**31)))  # OpenCV's generator: several times faster than numpy's normals
        cv2.randn(noise, 0.0, 1.0)
        noise *= np.sqrt(deviation, out=deviation)
        return cv2.add(signal, noise, dtype=cv2.CV_8U)  # rounded half to even and clipped to 0-255

    def _radiance(self, pose: np.ndarray, time_s: float, boards: tuple[FloorBoard, ...]) -> np.ndarray:
        """Noise-free grey levels (float32, H x W) for one pose at ``time_s``."""
        x, y, yaw = pose
        c, s = np.cos(yaw), np.sin(yaw)
        image = np.zeros(self.rig.camera.height * self.rig.camera.width, np.float32)
        x0, y0 = self.floor.origin
        to_texels = np.array([[c, -s, x - x0], [s, c, y - y0]]) / self.floor.texel  # base_link -> level-0 texels
        for group in self._groups:
            count = len(group.indices)
            level = min(group.level, len(self.floor.levels) - 1)
            lookup = cv2.transform(group.table, to_texels * 0.5**level)
            shade = self._texture(level, lookup)[:count]
            if group.weight.any() and level + 1 < len(self.floor.levels):
                lookup *= 0.5
                upper = self._texture(level + 1, lookup)[:count]
                upper -= shade
                upper *= group.weight
                shade += upper
            for sheet, levels in self._sheets:
                self._lay_sheet(shade, group, pose, time_s, sheet, levels)
            image[group.indices] = shade
        image = image.reshape(self.rig.camera.height, self.rig.camera.width)
        if self._ceiling is not None:
            image[self.hits_floor] += self._sheen(pose)
        self._draw_room(image, pose)
        for board in boards:
            self._draw_floor_board(image, pose, board)
        return image

    def _texture(self, level: int, lookup: np.ndarray) -> np.ndarray:
        """Bilinear samples (float32, flat) of the floor's mip ``level`` at the texel coordinates ``lookup``
        (rows, CHUNK, 2); beyond its edge the floor repeats mirrored."""
        sampled = cv2.remap(self.floor.levels[level], lookup, None, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT_101)
        return sampled.reshape(-1).astype(np.float32)

    def _lay_sheet(self, shade, group: _PixelGroup, pose, time_s, sheet: MovingSheet, levels) -> None:
        """Cover one pixel group's floor ``shade`` (N,) with ``sheet`` as it lies at ``time_s``, in place: each
        world point on the sheet takes the sheet's print at its sheet-frame position.

        ``levels`` is the sheet's own mip pyramid, looked up like the floor's. Groups out of reach are skipped.
        """
        x_min, y_min, x_max, y_max = group.box
        sheet_x, sheet_y, _ = sheet.pose(time_s)
        x, y, yaw = pose
        dx, dy = sheet_x - x, sheet_y - y
        c, s = np.cos(yaw), np.sin(yaw)
        ahead, left = c * dx + s * dy, c * dy - s * dx  # the sheet's centre in base_link
        reach = sheet.reach_m + (SHEET_PAD + 2) * self.floor.texel * 2**group.level  # its pad, blurred at this level
        if not (x_min - reach < ahead < x_max + reach and y_min - reach < left < y_max + reach):
            return
        points = group.points
        world_x = x + c * points[:, 0] - s * points[:, 1]
        world_y = y + s * points[:, 0] + c * points[:, 1]
        near = np.flatnonzero((np.abs(world_x - sheet_x) < reach) & (np.abs(world_y - sheet_y) < reach))
        if near.size == 0:
            return
        along, across = sheet.to_sheet(world_x[near], world_y[near], time_s)
        centre_u, centre_v = (levels[0].shape[1] - 1) / 2, (levels[0].shape[0] - 1) / 2
        texel = self.floor.texel
        weight = group.weight[near, None]
        printed = _trilinear(levels, group.level, weight, along / texel + centre_u, across / texel + centre_v)
        shade[near] = shade[near] * (1.0 - printed[:, 1]) + printed[:, 0]

    def _sheen(self, pose: np.ndarray) -> np.ndarray:
        """What the glossy floor mirrors of the ceiling's lamps, grey levels for the floor pixels (N,)."""
        x, y, yaw = pose
        to_world = np.array([[np.cos(yaw), -np.sin(yaw), x], [np.sin(yaw), np.cos(yaw), y]])
        world = cv2.transform(self._ceiling[:, None], to_world)[:, 0]
        return self.ceiling.mirrored(world[:, 0], world[:, 1])

    def _draw_room(self, image: np.ndarray, pose: np.ndarray) -> None:
        """Walls (brick) and ceiling (plain, with lamps) for the rays that miss the floor."""
        if self._off_floor.size == 0:
            return
        _, (centre_x, centre_y, centre_z) = camera_pose_in_world(self.rig, pose)
        c, s = np.float32(np.cos(pose[2])), np.float32(np.sin(pose[2]))
        base_x, base_y, ray_z = self._room_rays
        ray_x, ray_y = c * base_x - s * base_y, s * base_x + c * base_y
        x_min, x_max, y_min, y_max, top = self._room
        with np.errstate(divide="ignore", invalid="ignore"):
            # distance to the wall ahead over the speed towards it: +inf for a ray along the walls (never -inf)
            reach_x = np.where(ray_x > 0, np.float32(x_max - centre_x), np.float32(centre_x - x_min)) / np.abs(ray_x)
            reach_y = np.where(ray_y > 0, np.float32(y_max - centre_y), np.float32(centre_y - y_min)) / np.abs(ray_y)
            reach_z = np.where(ray_z > 0, np.float32(top - centre_z) / ray_z, np.float32(np.inf))
        to_wall = np.fmin(reach_x, reach_y)
        centre_x, centre_y = np.float32(centre_x), np.float32(centre_y)
        on_ceiling = reach_z <= to_wall
        shade = np.empty_like(ray_z)
        reach = reach_z[on_ceiling]
        hit_x = centre_x + reach * ray_x[on_ceiling]
        hit_y = centre_y + reach * ray_y[on_ceiling]
        shade[on_ceiling] = self.ceiling.shade(hit_x, hit_y)
        walls = ~on_ceiling
        reach = to_wall[walls]
        along_x = reach_x[walls] <= reach_y[walls]
        with np.errstate(invalid="ignore"):  # inf * 0 for a ray along a wall: in the branch not chosen
            along_wall = np.where(along_x, centre_y + reach * ray_y[walls], centre_x + reach * ray_x[walls])
        height = np.float32(top - centre_z) - reach * ray_z[walls]
        rows, cols = self._walls.shape
        u, v = wrap(along_wall / np.float32(0.016), cols), wrap(height / np.float32(0.016), rows)
        shade[walls] = np.float32(0.8) * _remap_points(self._walls, u, v, cv2.BORDER_WRAP)
        image.reshape(-1)[self._off_floor] = shade

    def _draw_floor_board(self, image: np.ndarray, pose: np.ndarray, board: FloorBoard) -> None:
        """Paint ``board`` over the floor, supersampled where it may cover a pixel."""
        x, y, yaw = pose
        c, s = np.cos(yaw), np.sin(yaw)
        points = self.floor_points
        world = np.stack([x + c * points[..., 0] - s * points[..., 1], y + s * points[..., 0] + c * points[..., 1]], -1)
        _, near = board.board.shade(board.to_board(world))
        rotation, centre = camera_pose_in_world(self.rig, pose)

        def board_points(rays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            rays = rotation.apply(rays.reshape(-1, 3)).reshape(rays.shape)
            with np.errstate(invalid="ignore", divide="ignore"):
                reach = -centre[2] / rays[..., 2]
            return board.to_board(centre[:2] + reach[..., None] * rays[..., :2]), reach > 0

        _paint_board(image, self.rig.camera, board.board, near & self.hits_floor, board_points)


def render_board_view(
    camera: CameraModel,
    board: Chessboard,
    board_in_camera: tuple[Rotation, np.ndarray],
    seed: int = 0,
    sensor: Sensor = Sensor(),
) -> np.ndarray:
    """A uint8 image of ``board`` held in front of ``camera`` against a plain, softly lit background.

    ``board_in_camera`` = (camera <- board rotation, board origin in the camera frame, metres).
    """
    rotation, origin = board_in_camera
    normal = rotation.apply([0.0, 0.0, 1.0])

    def board_points(rays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        with np.errstate(invalid="ignore", divide="ignore"):
            reach = (origin @ normal) / (rays @ normal)
        on_plane = reach[..., None] * rays - origin
        return rotation.inv().apply(on_plane.reshape(-1, 3)).reshape(rays.shape)[..., :2], reach > 0

    pixels = camera.pixel_grid()
    rays, valid = _pixel_rays(camera)
    centre_xy, in_front = board_points(rays)
    near = board.shade(centre_xy)[1] & in_front & valid
    u, v = pixels[..., 0], pixels[..., 1]
    image = (110.0 + 30.0 * np.cos(u / camera.width * np.pi) * np.sin(v / camera.height * np.pi)).astype(np.float32)
    _paint_board(image, camera, board, near, board_points)
    image[~valid] = 0.0
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal(image.shape) * np.sqrt(sensor.read_noise**2 + sensor.shot_noise**2 * image)
    return np.clip(np.rint(image + noise), 0, 255).astype(np.uint8)


@functools.lru_cache(maxsize=4)
def _pixel_rays(camera: CameraModel) -> tuple[np.ndarray, np.ndarray]:
    """Rays and validity of every pixel centre of ``camera``, kept for the next view of the same camera."""
    rays, valid = camera.unproject(camera.pixel_grid())
    rays.flags.writeable = valid.flags.writeable = False
    return rays, valid


def _paint_board(image, camera, board: Chessboard, near: np.ndarray, board_points, samples: int = 4) -> None:
    """Paint ``board`` into ``image`` (float, in place) with ``samples`` x ``samples`` rays per pixel.

    ``near`` marks the pixels whose centre ray hits the board; their neighbours are painted too.
    ``board_points(rays (..., 3) in the camera frame)`` returns the board-frame (x, y) where each
    ray meets the board's plane and whether it meets it in front of the camera.
    """
    near = cv2.dilate(near.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    if not near.any():
        return
    rows, cols = np.nonzero(near)
    offsets = (np.arange(samples) + 0.5) / samples - 0.5
    du, dv = np.meshgrid(offsets, offsets)
    pixels = np.stack([cols[:, None] + du.ravel(), rows[:, None] + dv.ravel()], axis=-1)
    rays, valid = camera.unproject(pixels)
    xy, in_front = board_points(rays)
    shade, on_board = board.shade(xy)
    on_board &= valid & in_front
    coverage = on_board.mean(axis=1)
    painted = np.where(on_board, BLACK + (WHITE - BLACK) * shade, 0.0).sum(axis=1) / samples**2
    image[rows, cols] = (1.0 - coverage) * image[rows, cols] + painted


def _trilinear(levels, level: int, weight, u0: np.ndarray, v0: np.ndarray, border=cv2.BORDER_CONSTANT) -> np.ndarray:
    """Mip-mapped lookup of level-0 texel coordinates (u0, v0) (N,): bilinear in mip ``level`` and the next,
    blended towards the next by ``weight`` ((N,), or (N, 1) for textures with channels). Levels past the
    pyramid's last use the last."""
    level = min(level, len(levels) - 1)
    lower = _remap_points(levels[level], u0 * 0.5**level, v0 * 0.5**level, border)
    if level + 1 < len(levels):
        upper = _remap_points(levels[level + 1], u0 * 0.5 ** (level + 1), v0 * 0.5 ** (level + 1), border)
        lower = (1.0 - weight) * lower + weight * upper
    return lower


def _remap_points(texture: np.ndarray, u: np.ndarray, v: np.ndarray, border: int) -> np.ndarray:
    """Bilinear samples of ``texture`` (H, W) or (H, W, C) at the points (u, v) (pixel units), as float32 (N,) or
    (N, C)."""
    count = len(u)
    rows = -(-count // CHUNK)
    map_u = np.zeros(rows * CHUNK, np.float32)
    map_v = np.zeros(rows * CHUNK, np.float32)
    map_u[:count], map_v[:count] = u, v
    sampled = cv2.remap(
        texture, map_u.reshape(rows, CHUNK), map_v.reshape(rows, CHUNK), cv2.INTER_LINEAR, borderMode=border
    )
    return sampled.reshape(rows * CHUNK, *texture.shape[2:])[:count].astype(np.float32)
