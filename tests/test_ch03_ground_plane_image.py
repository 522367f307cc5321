"""Chapter 03's figure of how far the GPI can reach: the rows one front-face pixel spreads over, against the
package's own refusal."""

import numpy as np
import pytest

from gpo.book.ch03_ground_plane_image import rows_per_face_pixel
from gpo.floor_image.gpi import MAX_MAGNIFICATION, ground_plane_image
from gpo.floor_image.image import GroundImageError
from gpo.sim.record import FLOOR_BOARDS, floor_board_image
from gpo.sim.rigs import t265_rig


@pytest.fixture(scope="module")
def setting():
    rig = t265_rig()
    return floor_board_image("t265"), rig.camera, FLOOR_BOARDS["t265"]


def test_a_face_pixel_spreads_over_more_rows_the_further_ahead(setting):
    gpi = ground_plane_image(*setting)
    ahead, stretch = rows_per_face_pixel(gpi, reach_m=1.0)
    assert ahead[0] == 0.0 and ahead[-1] == pytest.approx(1.0)
    assert np.all(np.diff(stretch) > 0)
    assert 0.5 < stretch[0] < 2.0  # about a row per face pixel at the seam


def test_the_stretch_crosses_the_limit_where_the_package_refuses(setting):
    gpi = ground_plane_image(*setting)
    ahead, stretch = rows_per_face_pixel(gpi, reach_m=1.0)
    crossing = ahead[np.argmax(stretch > MAX_MAGNIFICATION)]
    ground_plane_image(*setting, ahead_m=crossing - 0.02, cache=False)
    with pytest.raises(GroundImageError, match="hardly resolves"):
        ground_plane_image(*setting, ahead_m=crossing + 0.02, cache=False)
