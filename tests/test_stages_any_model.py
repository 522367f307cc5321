"""Every stage works with any camera model: the cubemap, the GPI, the ortho-GPI and the analytic floor image
built with a Kannala-Brandt (KB4) calibration of the simulated T265 agree with those built with its EUCM, to
within how closely the KB4 reproduces that EUCM. The motion stages (gpo.motion.klt, gpo.motion.keypoints) read only
floor images, never the camera model."""

import numpy as np
import pytest

from gpo.cameras import KB4
from gpo.cameras.fit import fit_model
from gpo.floor_image.analytic import analytic_table, route_difference
from gpo.floor_image.cubemap import Cubemap
from gpo.floor_image.image import FloorImage
from gpo.floor_image.ortho import chessboard_route
from gpo.sim.record import FLOOR_BOARDS, floor_board_image
from gpo.sim.rigs import t265_rig

RIG = t265_rig()
FINE_FLOOR = FloorImage.top_view(metres_per_pixel=0.5e-3)  # the chapters' floor patch at 0.5 mm per pixel


@pytest.fixture(scope="module", autouse=True)
def table_cache(tmp_path_factory):
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("GPO_CACHE_DIR", str(tmp_path_factory.mktemp("tables")))
        yield


@pytest.fixture(scope="module")
def kb4_fit():
    """The simulated T265's EUCM as a KB4, fitted over its image."""
    fit = fit_model(RIG.camera, "kb4")
    assert isinstance(fit.camera, KB4) and fit.uncovered == 0 and fit.worst_px < 0.15
    return fit


def test_cubemap_faces_of_a_kb4_camera(kb4_fit):
    eucm_cubemap, kb4_cubemap = Cubemap(RIG.camera), Cubemap(kb4_fit.camera)
    for name in ("front", "bottom", "left", "right", "top"):
        pixels = eucm_cubemap.faces[name].pinhole.pixel_grid()[::7, ::7]
        eucm_uv, eucm_valid = eucm_cubemap.face_to_fisheye(name, pixels)
        kb4_uv, kb4_valid = kb4_cubemap.face_to_fisheye(name, pixels)
        both = eucm_valid & kb4_valid
        assert both.sum() >= 0.99 * eucm_valid.sum()
        assert np.max(np.linalg.norm(kb4_uv[both] - eucm_uv[both], axis=-1)) <= kb4_fit.worst_px + 1e-3


def test_analytic_floor_image_of_a_kb4_camera(kb4_fit):
    eucm_table = analytic_table(RIG.camera, RIG.mount, FINE_FLOOR)
    kb4_table = analytic_table(kb4_fit.camera, RIG.mount, FINE_FLOOR)
    difference = route_difference(kb4_table, eucm_table)
    assert difference.common_fraction == 1.0 and difference.max_px <= kb4_fit.worst_px + 1e-3


def test_gpi_and_ortho_gpi_of_a_kb4_camera_from_the_chessboard(kb4_fit):
    frame = floor_board_image("t265", seed=0)
    eucm_route = chessboard_route(frame, RIG.camera, FLOOR_BOARDS["t265"], FINE_FLOOR)
    kb4_route = chessboard_route(frame, kb4_fit.camera, FLOOR_BOARDS["t265"], FINE_FLOOR)
    difference = route_difference(kb4_route.table, eucm_route.table)
    # the same board corners, found in faces that differ by at most 0.1 px: the two floor images agree closely
    assert difference.common_fraction > 0.99 and difference.max_px < 0.5 and difference.mean_mm < 0.2
    image = kb4_route.table.apply(frame)
    assert image.shape == eucm_route.table.apply(frame).shape and image.std() > 10.0
