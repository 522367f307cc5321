"""A run config proposed from what a bag holds and what is given: ``python -m gpo config`` and ``gpo run`` without one.

From the bag: the image topic (the only one, or the first with a camera_info beside it), its camera_info (the
factory calibration a driver publishes: realsense-ros writes a T265's as ``equidistant``, Kannala-Brandt), the
camera's frame (the images' ``frame_id``), the frame rate, /tf_static (the camera's optical frame in
``base_link``, composed along the static tree, e.g. base_link -> camera_pose_frame -> camera_link ->
camera_fisheye1_frame -> camera_fisheye1_optical_frame) and the tracking camera's odometry (nav_msgs/Odometry).
Given: ``--camera`` (a calibration file, in place of camera_info) and ``--mount`` (a mount section, as
``gpo mount`` writes it, in place of /tf_static). Every other setting is the shipped default config's.

The floor-image region (``floor_region``), in base_link (x forward, y left, z up, origin at the rear axle's
centre on the floor):

- a camera looking ahead (its optical axis more than ``DOWNWARD_BELOW_DEG`` from straight down): a square of
  ``REGION_PIXELS`` floor pixels on the floor line ahead of the camera, starting ``BODY_CLEARANCE`` camera heights
  ahead of the camera's foot, so that its rays are no steeper than atan(1 / BODY_CLEARANCE) below the horizon and
  the robot's own body, below and behind the camera, stays out of it;
- a camera looking down: a rectangle centred where the optical axis meets the floor, ``DOWN_FILL`` of the way to
  where the floor leaves the image along base_link's x and y;
- its pixel: the camera's footprint (metres per camera pixel, the geometric mean of both directions) at the
  region's near edge for a camera looking ahead, where it is finest, so that the floor image throws away none of
  the camera's detail; at the centre for a camera looking down, where it hardly changes;
- every point of it must project inside the image, ``MARGIN_PX`` from its border, through a valid ray.

The kinematic lever (the bicycle's wheelbase and rear-axle-to-reference distance) is the region's centre's
distance ahead of base_link: the floor's motion is measured there. A region centred less than ``MIN_LEVER_M``
ahead of the rear axle measures no turn through the lever: the method is then ``gpo-rigid``, the patch's own
rotation.
"""

from __future__ import annotations

import dataclasses
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from gpo.cameras.files import camera_to_kalibr
from gpo.cameras.mount import DOWNWARD_BELOW_DEG
from gpo.cameras.rig import CameraMount, Rig
from gpo.floor_image.image import FloorImage
from gpo.io.bag import Recording
from gpo.odometry.kinematics import PaperBicycle
from gpo.pipeline.config import DEFAULT_CONFIG, OdometryConfig, config_to_dict, load_config
from gpo.pipeline.schema import load_camera, load_mount

ODOMETRY_TYPE = "nav_msgs/msg/Odometry"
CAMERA_INFO_TYPE = "sensor_msgs/msg/CameraInfo"
BODY_CLEARANCE = 0.8
"""A forward camera's region starts this many camera heights ahead of the camera's foot."""
REGION_PIXELS = 200
"""A forward camera's region is this many floor pixels square: room for the KLT's 150 corners 8 px apart."""
DOWN_FILL = 0.8
"""A downward camera's region reaches this fraction of the way to where the floor leaves the image."""
MARGIN_PX = 16
"""The region keeps this far inside the camera image: half a KLT window and a little more."""
MIN_LEVER_M = 0.1
"""A region centred nearer than this ahead of the rear axle is read by ``gpo-rigid`` rather than through a lever."""
STEP_M = 1e-3
"""Footprints are measured over this floor step, metres."""
HEIGHT_AGREEMENT = 1.5
"""A mount given beside a bag's /tf_static may put the camera this many times higher or lower than /tf_static does: a
mount measured on the robot corrects a drawing's by centimetres, not by half its height."""


@dataclass
class Proposal:
    """A run ``config`` and, for each choice, the sentence saying where it came from (``sources``, by key of the
    config file: ``camera``, ``mount``, ``topics``, ``floor_image``, ...)."""

    config: OdometryConfig
    sources: dict[str, str] = field(default_factory=dict)


def propose(bag, camera_file=None, mount_file=None, topic: str | None = None) -> Proposal:
    """The run config for the bag ``bag`` from what it holds, ``camera_file`` (a calibration: Kalibr YAML, Basalt
    JSON, a run config) and ``mount_file`` (a YAML with a ``mount`` section). Errors say what to give instead."""
    default = load_config()
    sources: dict[str, str] = {}
    with Recording(bag) as recording:
        topics = {t.name: t for t in recording.topics()}
        image_topic = _image_topic(recording, topics, topic)
        info_topic = _info_topic(image_topic, topics)
        sources["topics"] = f"the bag: images on {image_topic}" + (
            f", camera_info on {info_topic}" if info_topic else ", no camera_info beside them"
        )
        frame = next(recording.frames(image_topic, progress=False), None)
        if frame is None:
            raise ValueError(f"{bag}: {image_topic} has no images")
        frame_id = frame.frame_id.lstrip("/")
        camera, sources["camera"] = _camera(recording, info_topic, camera_file)
        image_size = frame.image.shape[1], frame.image.shape[0]
        if (camera.width, camera.height) != image_size:
            raise ValueError(
                f"the camera ({sources['camera']}) is {camera.width} x {camera.height} pixels but the images on "
                f"{image_topic} are {image_size[0]} x {image_size[1]}: give this camera's calibration (--camera)"
            )
        mount, sources["mount"] = _mount_of(recording, frame_id, mount_file)
        rate = _rate(recording, topics[image_topic].count)
        sources["rate_hz"] = f"the bag: {topics[image_topic].count} images on {image_topic}"
        fusion, sources["fusion"] = _fusion(recording, topics, default)
    name = Path(bag).name.split(".")[0] or "robot"
    rig = Rig(name, camera, mount, rate, image_topic, info_topic or "", frame_id)
    floor, sources["floor_image"] = floor_region(camera, mount)
    centre_x = float(np.mean(floor.extent[:2]))
    lever = max(centre_x, MIN_LEVER_M)
    method = "gpo-exact" if centre_x >= MIN_LEVER_M else "gpo-rigid"
    sources["kinematics"] = (
        f"the floor region's centre, {centre_x:.3f} m ahead of base_link (the rear axle): the wheel the floor's motion "
        "is read at" if method == "gpo-exact"
        else f"the floor region's centre is {centre_x:.3f} m ahead of base_link, too near the rear axle for a lever: "
        "gpo-rigid reads the turn from the floor patch's own rotation (the lever is not used)"
    )
    sources["odometry"] = f"method {method}: " + (
        "the exact arc through the lever" if method == "gpo-exact" else "the floor patch's rigid motion"
    )
    config = default.replace(
        rig=rig, floor=floor, model=PaperBicycle(lever, lever), method=method, fusion=fusion, route="analytic"
    )
    sources["klt"] = sources["features"] = f"the shipped default ({DEFAULT_CONFIG})"
    return Proposal(config, sources)


def _image_topic(recording: Recording, topics: dict, topic: str | None) -> str:
    """``topic``, the bag's only image topic, or the first (by name) with a camera_info topic beside it."""
    if topic is not None:
        return recording.image_topic(topic)
    images = sorted(name for name, info in topics.items() if info.msgtype.endswith(("/Image", "/CompressedImage")))
    with_info = [name for name in images if _info_topic(name, topics)]
    if len(images) > 1 and with_info:
        return with_info[0]
    return recording.image_topic()


def _info_topic(image_topic: str, topics: dict) -> str | None:
    """The camera_info topic beside ``image_topic`` (``.../image_raw`` -> ``.../camera_info``), if the bag has it."""
    candidate = image_topic.rsplit("/", 1)[0] + "/camera_info"
    info = topics.get(candidate)
    return candidate if info is not None and info.msgtype == CAMERA_INFO_TYPE else None


def _camera(recording: Recording, info_topic: str | None, camera_file) -> tuple:
    """The camera from ``camera_file`` or else the bag's camera_info, and where it came from."""
    if camera_file is not None:
        return load_camera(camera_file), f"--camera {camera_file}"
    if info_topic is None:
        raise ValueError(
            f"{recording.path} has no camera_info beside its images: give the camera's calibration with --camera "
            "CALIB (a Kalibr camchain as gpo calibrate writes it, a Basalt JSON or a run config)"
        )
    try:
        camera = recording.camera_info(info_topic)
        if not (camera.fx > 0 and camera.fy > 0 and 0 < camera.cx < camera.width and 0 < camera.cy < camera.height):
            raise ValueError(
                f"its camera matrix is fx {camera.fx}, fy {camera.fy}, cx {camera.cx}, cy {camera.cy}: not a "
                "calibration (zeros are what a driver writes when it has none)"
            )
    except (ValueError, TypeError) as error:
        raise ValueError(
            f"{recording.path}, {info_topic}: {error}. Give the camera's calibration with --camera CALIB instead "
            "(gpo calibrate makes one from chessboard images)"
        ) from None
    return camera, f"the bag's {info_topic} (the driver's factory calibration, {type(camera).__name__})"


def static_tree(recording: Recording) -> dict[str, tuple[str, np.ndarray, Rotation]]:
    """/tf_static as child -> (parent, translation m, rotation parent <- child), the last one of each child winning;
    empty when the bag has no /tf_static."""
    return {
        child: (parent, translation, Rotation.from_quat(quaternion))
        for child, (parent, translation, quaternion) in recording.static_transforms().items()
    }


def chain(tree: dict, parent: str, child: str) -> tuple[Rotation, np.ndarray, list[str]] | None:
    """``child``'s pose in ``parent`` (rotation parent <- child, translation m) along the static ``tree`` and the
    frames walked from ``child`` up to ``parent``, or None when ``child`` does not lead up to ``parent``."""
    rotation, translation, frames = Rotation.identity(), np.zeros(3), [child]
    while frames[-1] != parent:
        if frames[-1] not in tree:
            return None
        up, step_translation, step_rotation = tree[frames[-1]]
        rotation, translation = step_rotation * rotation, step_rotation.apply(translation) + step_translation
        frames.append(up)
    return rotation, translation, frames


def _mount_of(recording: Recording, frame_id: str, mount_file) -> tuple[CameraMount, str]:
    """The camera's optical frame in base_link: from ``mount_file`` or else the bag's /tf_static, and its source. A
    ``mount_file`` whose height differs from /tf_static's more than ``HEIGHT_AGREEMENT`` times is refused."""
    tree = static_tree(recording)
    found = chain(tree, "base_link", frame_id)
    if mount_file is not None:
        mount = check_mount(load_mount(mount_file), str(mount_file))
        if found is not None:
            _check_heights_agree(mount, found[1][2], mount_file, recording.path)
        return mount, f"--mount {mount_file}"
    if found is None:
        held = ", ".join(f"{parent} -> {child}" for child, (parent, _, _) in sorted(tree.items())) or "nothing"
        raise ValueError(
            f"{recording.path}: /tf_static does not lead from base_link to the camera's frame {frame_id} (it holds "
            f"{held}): give the mount with --mount mount.yaml (gpo mount measures it from a board on the floor)"
        )
    rotation, translation, frames = found
    return check_mount(CameraMount(translation, rotation), "/tf_static"), "the bag's /tf_static: " + " -> ".join(
        reversed(frames)
    )


def check_mount(mount: CameraMount, source: str) -> CameraMount:
    """``mount`` checked to be above the floor; ValueError naming ``source`` otherwise."""
    if not mount.height > 0:
        raise ValueError(
            f"{source}: the camera sits {mount.height:.3f} m above the floor, at or below it; the mount is base_link "
            "-> the camera, base_link on the floor with z up (REP-103)"
        )
    return mount


def _check_heights_agree(mount: CameraMount, static_height: float, mount_file, bag) -> None:
    """ValueError when the height of ``mount`` (from ``mount_file``) and the bag's /tf_static height of the camera
    differ by more than ``HEIGHT_AGREEMENT`` times: a board's square size given wrong to ``gpo mount``, most often."""
    ratio = mount.height / static_height if static_height > 0 else np.inf
    if not 1 / HEIGHT_AGREEMENT <= ratio <= HEIGHT_AGREEMENT:
        raise ValueError(
            f"--mount {mount_file} puts the camera {mount.height:.3f} m above the floor, {bag}'s /tf_static "
            f"{static_height:.3f} m: one of them is wrong (gpo mount's height scales with --square, the board's "
            "square size); measure the mount again, or leave out --mount to take /tf_static's"
        )


def _rate(recording: Recording, count: int) -> float:
    """Frames per second: the image count over the bag's duration (30 for a bag of one frame)."""
    return round((count - 1) / recording.duration_s, 2) if count > 1 and recording.duration_s > 0 else 30.0


def _fusion(recording: Recording, topics: dict, default: OdometryConfig):
    """The fusion settings: the tracking camera's odometry topic and frame from the bag, when it has one."""
    odometry = sorted(name for name, info in topics.items() if info.msgtype == ODOMETRY_TYPE)
    if not odometry:
        return default.fusion, "no tracking odometry (nav_msgs/Odometry) in the bag: --method fused cannot run"
    topic = default.fusion.tracking_topic if default.fusion.tracking_topic in odometry else odometry[0]
    _, child = recording.pose_frames(topic)  # the first message: an 80 m bag holds 27 000
    settings = dataclasses.replace(default.fusion, tracking_topic=topic, tracking_frame=child)
    return settings, f"the bag: tracking odometry on {topic}, of {child} (--method fused uses it)"


def footprint(camera, mount: CameraMount, point) -> float:
    """Metres of floor per camera pixel at the floor ``point`` (x, y) in base_link: the geometric mean over x and y."""
    points = np.array([[0.0, 0.0], [STEP_M, 0.0], [0.0, STEP_M]]) + np.asarray(point, dtype=float)
    pixels, valid = _project(camera, mount, points)
    if not valid.all():
        return float("nan")
    stretch = np.linalg.norm(pixels[1:] - pixels[0], axis=1)
    return float(STEP_M / np.sqrt(stretch[0] * stretch[1]))


def _project(camera, mount: CameraMount, floor_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixels (N, 2) of floor points (N, 2) in base_link and whether each lies in the image, ``MARGIN_PX`` in."""
    points = np.column_stack([floor_xy, np.zeros(len(floor_xy))])
    pixels, valid = camera.project(mount.to_camera(points))
    pixels = np.nan_to_num(pixels, nan=-1e9)
    inside = (pixels >= MARGIN_PX).all(axis=1) & (pixels[:, 0] <= camera.width - 1 - MARGIN_PX)
    inside &= pixels[:, 1] <= camera.height - 1 - MARGIN_PX
    return pixels, valid & inside


def floor_region(camera, mount: CameraMount) -> tuple[FloorImage, str]:
    """The floor image for ``camera`` at ``mount`` (see the module docstring) and a sentence saying how it was
    chosen; ValueError when the camera does not see the floor there."""
    check_mount(mount, "the mount")
    height = mount.height
    axis = mount.rotation.apply([0.0, 0.0, 1.0])
    foot = mount.position[:2]
    if -axis[2] > np.cos(np.radians(DOWNWARD_BELOW_DEG)):
        centre = foot - height * axis[:2] / axis[2]
        half = [DOWN_FILL * _reach(camera, mount, centre, direction) for direction in np.eye(2)]
        scale = footprint(camera, mount, centre)
        how = (
            f"the camera looks down: centred where its axis meets the floor, {DOWN_FILL:.0%} of the way to where the "
            f"floor leaves the image; pixel = the camera's footprint there"
        )
    else:
        forward = mount.body_rotation.apply([1.0, 0.0, 0.0])[:2]
        if np.linalg.norm(forward) < 1e-6:
            raise ValueError("the camera looks straight up or down along its body's x axis: no floor ahead of it")
        forward /= np.linalg.norm(forward)
        near = foot + BODY_CLEARANCE * height * forward
        scale = float(np.round(footprint(camera, mount, near), 4))
        centre = near + REGION_PIXELS * scale / 2.0 * forward
        half = [REGION_PIXELS * scale / 2.0] * 2
        how = (
            f"the camera looks ahead: {REGION_PIXELS} x {REGION_PIXELS} floor pixels on its line of sight, starting "
            f"{BODY_CLEARANCE} camera heights ({BODY_CLEARANCE * height:.3f} m) ahead of its foot, clear of the robot's"
            " body; pixel = the camera's footprint at its near edge, the finest in it"
        )
    if not np.isfinite(scale):
        raise ValueError(_unseen(mount, centre))
    scale = float(np.round(scale, 4)) or 1e-4
    x_range = (round(centre[0] - half[0], 3), round(centre[0] + half[0], 3))
    y_range = (round(centre[1] - half[1], 3), round(centre[1] + half[1], 3))
    check_region(camera, mount, x_range, y_range)
    return FloorImage.top_view(x_range, y_range, scale), how


def _reach(camera, mount: CameraMount, centre: np.ndarray, direction: np.ndarray) -> float:
    """How far from ``centre`` along ±``direction`` the floor stays in the image (the nearer side), metres."""
    steps = np.arange(1, 4000) * STEP_M
    reach = []
    for sign in (1.0, -1.0):
        _, inside = _project(camera, mount, centre + sign * steps[:, None] * direction)
        reach.append(steps[np.argmin(inside)] if not inside.all() else steps[-1])
    return float(min(reach))


def check_region(camera, mount: CameraMount, x_range, y_range) -> None:
    """ValueError unless every point of the floor rectangle (base_link, metres) is seen ``MARGIN_PX`` inside the
    image through a valid ray."""
    grid = np.stack(np.meshgrid(np.linspace(*x_range, 21), np.linspace(*y_range, 21)), axis=-1).reshape(-1, 2)
    _, inside = _project(camera, mount, grid)
    if not inside.all():
        raise ValueError(
            f"the floor region x {list(x_range)} m, y {list(y_range)} m is {1 - inside.mean():.0%} outside the image "
            f"(or beyond the lens's view) with this mount: {_mount_text(mount)}. Check the mount (a camera pitched "
            "up or too high sees no floor there), or give a region the camera sees"
        )


def _unseen(mount: CameraMount, centre) -> str:
    return (
        f"the camera does not see the floor at ({centre[0]:.2f}, {centre[1]:.2f}) m with this mount: "
        f"{_mount_text(mount)}; a pitch beyond the lens's view of the floor, or a wrong mount"
    )


def _mount_text(mount: CameraMount) -> str:
    roll, pitch, yaw = np.degrees(mount.body_rpy)
    return f"height {mount.height:.3f} m, roll {roll:.1f}, pitch {pitch:.1f}, yaw {yaw:.1f} deg"


def proposal_yaml(proposal: Proposal, source: str) -> str:
    """The config of ``proposal`` as YAML with each choice explained in a comment above its section."""
    document = config_to_dict(proposal.config)
    sources = {**proposal.sources, "name": "the bag's name", "frame_id": "the images' frame_id"}
    lines = _comment(f"gpo run config proposed by gpo config from {source}; each section says where it came from")
    for key, value in document.items():
        if key in sources:
            lines += _comment(f"{key}: {sources[key]}")
        flow = None if isinstance(value, dict) else False  # a scalar alone in flow style would be {key: value}
        lines.append(yaml.safe_dump({key: value}, sort_keys=False, default_flow_style=flow, width=110).rstrip())
    return "\n".join(lines) + "\n"


def _comment(text: str) -> list[str]:
    return ["# " + line for line in textwrap.wrap(text, 116)]


def print_sources(proposal: Proposal) -> None:
    """Where each value of ``proposal`` came from, one line each."""
    config = proposal.config
    x_min, x_max, y_min, y_max = config.floor.extent
    values = {
        "camera": proposal.sources["camera"],
        "mount": f"{_mount_text(config.rig.mount)}; from {proposal.sources['mount']}",
        "topics": proposal.sources["topics"],
        "floor_image": f"x {x_min:.3f}..{x_max:.3f} m, y {y_min:.3f}..{y_max:.3f} m, "
        f"{config.floor.metres_per_pixel * 1e3:.2f} mm pixels: {proposal.sources['floor_image']}",
        "kinematics": f"lever {config.model.wheelbase_m:.3f} m: {proposal.sources['kinematics']}",
        "fusion": proposal.sources["fusion"],
    }
    for key, text in values.items():
        print(f"{key:<12} {text}")


def config_from_bag(bag, topic: str | None = None) -> tuple[OdometryConfig, str]:
    """The config ``gpo run`` uses without ``--config``, and its name: the shipped default when the bag's camera and
    mount are its rig's (it was tuned for it), else the proposal from what the bag holds, or the shipped default
    when the bag does not describe its rig (saying why). Prints where each value came from."""
    default = load_config()
    try:
        proposal = propose(bag, topic=topic)
    except ValueError as error:
        print(f"config: the shipped default ({DEFAULT_CONFIG}); the bag alone does not describe its rig: {error}")
        return default, f"the default, {DEFAULT_CONFIG}"
    rig, shipped = proposal.config.rig, default.rig
    same_mount = np.allclose(rig.mount.position, shipped.mount.position, atol=1e-6) and (
        (rig.mount.rotation.inv() * shipped.mount.rotation).magnitude() < 1e-6
    )
    if same_mount and camera_to_kalibr(rig.camera, "") == camera_to_kalibr(shipped.camera, ""):
        print(f"config: the shipped default ({DEFAULT_CONFIG}): the bag's camera_info and /tf_static are its rig's")
        return default, f"the default, {DEFAULT_CONFIG}"
    print("config: proposed from the bag (gpo config writes it as a file to edit):")
    print_sources(proposal)
    return proposal.config, f"proposed from {bag}"
