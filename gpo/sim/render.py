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
reflection of the ceiling lamps, which does not move with the floor.

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

from gpo.camera import EUCM, Pinhole
from gpo.rig import Rig, floor_points, rays_in_base
from gpo.sim.floors import FloorTexture
from gpo.targets import Chessboard, FloorBoard

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


class FloorRenderer:
    """Renders ``rig``'s view of ``floor`` for robot poses; everything that does not move is precomputed.

    ``room_margin`` metres of floor surround the texture before the walls rise ``room_height``
    metres high. The texture repeats mirrored beyond its edge, where it is far and small.
    """

    def __init__(self, rig: Rig, floor: FloorTexture, sensor: Sensor = Sensor(), room_margin=3.0, room_height=2.8):
        self.rig, self.floor, self.sensor = rig, floor, sensor
        camera = rig.camera
        self._rays_base, valid = rays_in_base(rig, camera.pixel_grid())
        floor_xy, hits_floor = floor_points(rig, self._rays_base)
        hits_floor &= valid
        self.hits_floor, self.valid = hits_floor, valid
        self.floor_points = floor_xy  # (H, W, 2) metres in base_link, NaN where the ray misses the floor
        self._levels = self._mip_levels(floor_xy, hits_floor)
        self._groups = self._group_by_level(floor_xy, self._levels, hits_floor)
        x_min, x_max, y_min, y_max = floor.extent
        self._room = (x_min - room_margin, x_max + room_margin, y_min - room_margin, y_max + room_margin, room_height)
        self._walls = cv2.pyrDown(cv2.pyrDown(skimage.data.brick())).astype(np.float32)
        self._off_floor = np.flatnonzero((valid & ~hits_floor).ravel())
        angle = np.arccos(np.clip(self._rays_base @ rig.mount.rotation.apply([0.0, 0.0, 1.0]), -1.0, 1.0))
        self._vignetting = np.where(valid, 1.0 - sensor.vignetting * (np.sin(np.minimum(angle, np.pi / 2)) ** 2), 0.0)

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
    def _group_by_level(floor_xy, levels, hits_floor) -> list[tuple[int, np.ndarray, np.ndarray, np.ndarray]]:
        """Pixels grouped by their lower mip level: (level, flat indices, floor points (N, 2), blend weight)."""
        flat = np.flatnonzero(hits_floor.ravel())
        lower = np.floor(levels.ravel()[flat]).astype(int)
        groups = []
        for level in np.unique(lower):
            chosen = flat[lower == level]
            weight = levels.ravel()[chosen] - level
            groups.append((int(level), chosen, floor_xy.reshape(-1, 2)[chosen].astype(np.float64), weight))
        return groups

    def render(self, poses, frame_seed: int | tuple = 0, boards: tuple[FloorBoard, ...] = ()) -> np.ndarray:
        """The uint8 image for robot pose(s) (x, y, yaw) in metres and radians.

        ``poses`` (3,) or (K, 3): K poses are averaged (motion blur over the exposure).
        ``frame_seed`` seeds this frame's noise and flicker, so frames render alike in any order.
        """
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        radiance = np.mean([self._radiance(pose, boards) for pose in poses], axis=0)
        rng = np.random.default_rng(frame_seed)
        gain = 1.0 + self.sensor.flicker * rng.standard_normal()
        signal = radiance * self._vignetting * gain
        noise = rng.standard_normal(signal.shape) * np.sqrt(
            self.sensor.read_noise**2 + self.sensor.shot_noise**2 * np.maximum(signal, 0.0)
        )
        return np.clip(np.rint(signal + noise), 0, 255).astype(np.uint8)

    def _radiance(self, pose: np.ndarray, boards: tuple[FloorBoard, ...]) -> np.ndarray:
        """Noise-free grey levels (float, H x W) for one pose."""
        x, y, yaw = pose
        c, s = np.cos(yaw), np.sin(yaw)
        image = np.zeros(self.rig.camera.height * self.rig.camera.width, np.float32)
        x0, y0 = self.floor.origin
        for level, indices, points, weight in self._groups:
            world_x = x + c * points[:, 0] - s * points[:, 1]
            world_y = y + s * points[:, 0] + c * points[:, 1]
            lower = self._sample(level, (world_x - x0) / self.floor.texel, (world_y - y0) / self.floor.texel)
            if level + 1 < len(self.floor.levels):
                upper = self._sample(level + 1, (world_x - x0) / self.floor.texel, (world_y - y0) / self.floor.texel)
                lower = (1.0 - weight) * lower + weight * upper
            image[indices] = lower
        image = image.reshape(self.rig.camera.height, self.rig.camera.width)
        if self.floor.sheen:
            image += self._sheen(pose)
        self._draw_room(image, pose)
        for board in boards:
            self._draw_floor_board(image, pose, board)
        return image

    def _sample(self, level: int, u0: np.ndarray, v0: np.ndarray) -> np.ndarray:
        """Bilinear lookup of level-0 texel coordinates (u0, v0) in mip ``level``."""
        scale = 0.5**level
        return _remap_points(self.floor.levels[level], u0 * scale, v0 * scale, cv2.BORDER_REFLECT_101)

    def _sheen(self, pose: np.ndarray) -> np.ndarray:
        """A soft highlight where the floor mirrors the ceiling lamps (rows of 1.2 m x 0.3 m lamps, 2.4 m apart)."""
        sheen = np.zeros(self.hits_floor.shape, np.float32)
        rays = self._rays_base[self.hits_floor]
        points = self.floor_points[self.hits_floor]
        room_height = self._room[4]
        reach = room_height / -rays[:, 2]
        ceiling = points + reach[:, None] * rays[:, :2]  # the mirrored ray rises as the real one fell
        x, y, yaw = pose
        c, s = np.cos(yaw), np.sin(yaw)
        world = np.column_stack([x + c * ceiling[:, 0] - s * ceiling[:, 1], y + s * ceiling[:, 0] + c * ceiling[:, 1]])
        du = (world[:, 0] % 2.4) - 1.2
        dv = (world[:, 1] % 2.4) - 1.2
        glow = np.exp(-((np.maximum(np.abs(du) - 0.6, 0) / 0.25) ** 2) - (np.maximum(np.abs(dv) - 0.15, 0) / 0.25) ** 2)
        sheen[self.hits_floor] = 60.0 * glow
        return sheen

    def _draw_room(self, image: np.ndarray, pose: np.ndarray) -> None:
        """Walls (brick) and ceiling (plain, with lamps) for the rays that miss the floor."""
        if self._off_floor.size == 0:
            return
        _, centre = camera_pose_in_world(self.rig, pose)
        rays = Rotation.from_euler("z", pose[2]).apply(self._rays_base.reshape(-1, 3)[self._off_floor])
        x_min, x_max, y_min, y_max, top = self._room
        with np.errstate(divide="ignore", invalid="ignore"):
            reach_x = np.where(rays[:, 0] > 0, (x_max - centre[0]) / rays[:, 0], (x_min - centre[0]) / rays[:, 0])
            reach_y = np.where(rays[:, 1] > 0, (y_max - centre[1]) / rays[:, 1], (y_min - centre[1]) / rays[:, 1])
            reach_z = np.where(rays[:, 2] > 0, (top - centre[2]) / rays[:, 2], np.inf)
        reach = np.fmin(np.fmin(reach_x, reach_y), reach_z)
        hit = centre + reach[:, None] * rays
        along_wall = np.where(reach_x <= reach_y, hit[:, 1], hit[:, 0])
        wall = _remap_points(self._walls, along_wall / 0.016, (top - hit[:, 2]) / 0.016, cv2.BORDER_WRAP)
        lamps = 230.0 * ((np.abs((hit[:, 0] % 2.4) - 1.2) < 0.6) & (np.abs((hit[:, 1] % 2.4) - 1.2) < 0.15))
        on_ceiling = reach_z <= np.fmin(reach_x, reach_y)
        image.reshape(-1)[self._off_floor] = np.where(on_ceiling, np.maximum(170.0, lamps), 0.8 * wall)

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
    camera: EUCM | Pinhole,
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
def _pixel_rays(camera: EUCM | Pinhole) -> tuple[np.ndarray, np.ndarray]:
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


def _remap_points(texture: np.ndarray, u: np.ndarray, v: np.ndarray, border: int) -> np.ndarray:
    """Bilinear samples of ``texture`` at the points (u, v) (pixel units), as float32 (N,)."""
    count = len(u)
    rows = -(-count // CHUNK)
    map_u = np.zeros(rows * CHUNK, np.float32)
    map_v = np.zeros(rows * CHUNK, np.float32)
    map_u[:count], map_v[:count] = u, v
    sampled = cv2.remap(
        texture, map_u.reshape(rows, CHUNK), map_v.reshape(rows, CHUNK), cv2.INTER_LINEAR, borderMode=border
    )
    return sampled.reshape(-1)[:count].astype(np.float32)
