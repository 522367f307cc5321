"""The ROS messages that ``gpo.io.bag`` reads and ``gpo.io.bag_writer`` writes: their type names, image
encodings and codecs, and the conventions both directions keep.

Message types are named the ROS2 way (``sensor_msgs/msg/Image``) for ROS1 bags too, as
`rosbags <https://gitlab.com/ternaris/rosbags>`_ names them.

Frames and units
----------------
Frames follow REP-103/105. A transform or pose of ``child`` in ``parent`` (``frame_id``) maps
child-frame coordinates into the parent frame: translation in metres, rotation as a unit
quaternion (x, y, z, w), as tf does. Odometry twists are in the child frame, in m/s and rad/s.

Images
------
Raw ``sensor_msgs/msg/Image`` encodings read and written: mono8, mono16, rgb8, bgr8, rgba8, bgra8.
``sensor_msgs/msg/CompressedImage`` in jpeg or png follows image_transport: ``format`` reads
``"<encoding>; <codec> compressed <coded encoding>"`` (older bags: just ``"jpeg"``); colour is coded
as BGR, so a colour frame comes back as bgr8/bgra8, or as rgb8/rgba8 when ``format`` names that as
the original encoding. 16-bit PNG keeps its 16 bits.

Cameras
-------
``sensor_msgs/msg/CameraInfo`` holds fx, fy, cx, cy in ``K``. Distortion models: ``plumb_bob`` and
``rational_polynomial`` give a ``Pinhole`` (D = k1, k2, p1, p2[, k3]; rational_polynomial only when
its k4, k5, k6 are zero); ``equidistant`` a ``KB4`` (D = k1, k2, k3, k4); ``eucm`` and ``ds``, this
project's conventions, an ``EUCM`` (D = alpha, beta) and a ``DoubleSphere`` (D = xi, alpha), as
`gpo.cameras.files.camera_from_camera_info` reads them.
"""

from __future__ import annotations

import numpy as np

IMAGE = "sensor_msgs/msg/Image"
COMPRESSED_IMAGE = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
ODOMETRY = "nav_msgs/msg/Odometry"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
TRANSFORM_STAMPED = "geometry_msgs/msg/TransformStamped"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
IMAGE_TYPES = (IMAGE, COMPRESSED_IMAGE)
POSE_TYPES = (ODOMETRY, POSE_STAMPED, TRANSFORM_STAMPED)

ENCODINGS: dict[str, tuple[type[np.integer], int]] = {
    "mono8": (np.uint8, 1),
    "mono16": (np.uint16, 1),
    "rgb8": (np.uint8, 3),
    "bgr8": (np.uint8, 3),
    "rgba8": (np.uint8, 4),
    "bgra8": (np.uint8, 4),
}
"""Raw image encodings read and written: element type and channels."""

CODECS = ("jpeg", "png")
"""CompressedImage codecs read and written."""


def check_encoding(image: np.ndarray, encoding: str | None, context: str, colour: str = "rgb") -> str:
    """``encoding`` checked against ``image``'s dtype and shape, or inferred from them when None.

    An inferred 3- or 4-channel image is taken to be in ``colour`` channel order ("rgb" or "bgr").
    """
    kind = (image.dtype.type, image.shape[2] if image.ndim == 3 else 1)
    if encoding is None:
        inferred = {
            (np.uint8, 1): "mono8",
            (np.uint16, 1): "mono16",
            (np.uint8, 3): f"{colour}8",
            (np.uint8, 4): f"{colour}a8",
        }
        encoding = inferred.get(kind)
    if image.ndim not in (2, 3) or ENCODINGS.get(encoding) != kind:
        supported = ", ".join(f"{name} ({np.dtype(t).name} x{c})" for name, (t, c) in ENCODINGS.items())
        raise ValueError(
            f"{context}: a {image.dtype} image of shape {image.shape} is not {encoding or 'any encoding'}; "
            f"supported: {supported}"
        )
    return encoding
