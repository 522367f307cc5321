"""Camera models, and a camera on a robot: the core every other part of gpo stands on.

One module per model, each a subclass of `CameraModel` (``base``): ``eucm`` (the first paper's EUCM), ``pinhole``
(with OpenCV's radial-tangential distortion), ``omni`` (Mei's unified model), ``kb4`` (Kannala-Brandt) and
``double_sphere``; ``MODELS`` registers them by the name configs and the command line use. Beside them: ``files``
(Kalibr, Basalt, ROS camera_info and BoofCV calibrations), ``fit`` (one model fitted to another), ``chessboard``
(finding a board's corners), ``calibrate`` (a model's intrinsics from chessboard views), ``targets`` (chessboards,
and one lying on the floor), ``rig`` (a camera's mount on the robot), ``mount`` (that mount measured from a board
on the floor) and ``straightness`` (a model checked on real images by straight lines).

A new camera model is one module with a `CameraModel` subclass and one line in ``MODELS``.
"""

from gpo.cameras.base import CameraModel
from gpo.cameras.double_sphere import DoubleSphere
from gpo.cameras.eucm import EUCM, T265_LIKE
from gpo.cameras.kb4 import KB4
from gpo.cameras.omni import Omni
from gpo.cameras.pinhole import Pinhole

MODELS: dict[str, type[CameraModel]] = {"eucm": EUCM, "ds": DoubleSphere, "kb4": KB4, "omni": Omni, "pinhole": Pinhole}
"""Camera model classes by the name the command line and the config use."""

__all__ = ["EUCM", "KB4", "MODELS", "T265_LIKE", "CameraModel", "DoubleSphere", "Omni", "Pinhole"]
