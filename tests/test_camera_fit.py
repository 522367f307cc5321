"""Model-to-model fits over the image: exact where the models coincide, and the T265's KB4 as the other models."""

import numpy as np
import pytest

from gpo.cameras import EUCM, KB4, DoubleSphere, Omni, Pinhole
from gpo.cameras.files import load_basalt
from gpo.cameras.fit import fit_model, local_focal, model_name, parameter_bounds


@pytest.mark.parametrize("alpha", [0.4, 0.62])
def test_a_double_sphere_with_xi_zero_is_the_eucm_with_beta_one(alpha):
    ds = DoubleSphere(286.0, 286.2, 424.3, 400.1, 0.0, alpha, 848, 800)
    fit = fit_model(ds, "eucm")
    np.testing.assert_allclose(fit.camera.params, [286.0, 286.2, 424.3, 400.1, alpha, 1.0], rtol=1e-7)
    assert fit.worst_px < 1e-6 and fit.uncovered == 0


@pytest.mark.parametrize("xi", [0.5, 1.2])
def test_undistorted_omni_is_the_eucm_with_alpha_xi_over_one_plus_xi(xi):
    omni = Omni(400.0, 401.0, 319.0, 360.0, xi, (0.0,) * 4, 640, 720)
    fit = fit_model(omni, "eucm")
    expected = [400.0 / (1 + xi), 401.0 / (1 + xi), 319.0, 360.0, xi / (1 + xi), 1.0]
    np.testing.assert_allclose(fit.camera.params, expected, rtol=1e-7)
    assert fit.worst_px < 1e-6


def test_a_model_fitted_to_itself_from_another_start_is_itself():
    kb4 = KB4(286.6, 286.5, 422.3, 395.2, k1=-0.0068, k2=0.045, k3=-0.0435, k4=0.0084, width=848, height=800)
    fit = fit_model(kb4, "kb4")
    np.testing.assert_allclose(fit.camera.params, kb4.params, rtol=1e-7, atol=1e-9)
    assert fit.worst_px < 1e-6 and fit.summary() == "kb4 -> kb4 over 2650 pixels: RMS 0.0000 px, worst 0.0000 px"


def test_the_real_t265_kb4_as_eucm_double_sphere_and_omni(fetch_or_skip):
    kb4 = load_basalt(fetch_or_skip("basalt/data/t265_kb4_calib.json"))[0]
    # within 80 degrees of the axis (the T265 sees about 163 degrees; the image's corners lie beyond its circle)
    fits = {model: fit_model(kb4, model, max_angle_deg=80.0) for model in ("eucm", "ds", "omni")}
    for fit in fits.values():
        assert fit.samples == 1803 and fit.uncovered == 0
        # the principal point stays the KB4's: measured 0.003 px off at most (the double sphere's)
        assert abs(fit.camera.cx - kb4.cx) < 0.006 and abs(fit.camera.cy - kb4.cy) < 0.006
    # measured (the same on the avx2 and sse4 paths, .ci/fp-path): RMS and worst 0.148 and 0.488 px (eucm), 0.094 and
    # 0.376 px (omni), 1.012 and 4.09 px (ds: the double sphere holds this lens least well)
    assert fits["eucm"].rms_px < 0.2 and fits["eucm"].worst_px < 0.6
    assert fits["omni"].rms_px < 0.15 and fits["omni"].worst_px < 0.5
    assert fits["ds"].rms_px < 1.1 and fits["ds"].worst_px < 4.5
    # and each fit's own round trip holds over every pixel it has a ray for
    for fit in fits.values():
        pixels = fit.camera.pixel_grid()[::3, ::3]
        rays, valid = fit.camera.unproject(pixels)
        back, _ = fit.camera.project(rays[valid])
        assert valid.mean() > 0.7 and np.max(np.abs(back - pixels[valid])) < 1e-6


def test_pixels_the_target_cannot_see_are_counted():
    wide = KB4(200.0, 200.0, 424.0, 400.0, 0.0, 0.0, 0.0, 0.0, 848, 800)  # 848 px wide at 200 px/rad: 243 degrees
    fit = fit_model(wide, "eucm")
    assert fit.uncovered > 0 and "pixels the eucm model cannot see" in fit.summary()


def test_what_cannot_be_fitted_is_refused():
    with pytest.raises(ValueError, match="cannot fit the camera model 'pinhole'; choose one of eucm, ds, kb4, omni"):
        fit_model(EUCM(286.0, 286.0, 424.0, 400.0, 0.6, 1.1, 848, 800), "pinhole")
    with pytest.raises(ValueError, match="cannot fit the camera model 'fov'"):
        parameter_bounds("fov")


def test_names_and_local_focal_length():
    pinhole = Pinhole(500.0, 500.0, 320.0, 240.0, (0.0,) * 4, 640, 480)
    assert model_name(pinhole) == "pinhole" and model_name(DoubleSphere(1, 1, 0, 0, 0, 0.5, 4, 4)) == "ds"
    assert local_focal(pinhole) == pytest.approx(500.0, rel=1e-5)
    with pytest.raises(TypeError, match="not a camera model"):
        model_name(object())
