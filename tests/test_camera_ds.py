"""Double sphere against the formulas of Usenko, Demmel and Cremers (3DV 2018), written here again
independently, and round trips over the whole image of a T265-sized lens."""

import numpy as np
import pytest

from gpo.cameras import EUCM, DoubleSphere

# Basalt's published calibration of the TUM VI 512 left camera (basalt/data/tumvi_512_ds_calib.json, cam0)
TUMVI = DoubleSphere(
    fx=158.28600034966976,
    fy=158.2743455478755,
    cx=254.96116578191652,
    cy=256.8894394501779,
    xi=-0.17213086034353242,
    alpha=0.5931177593944744,
    width=512,
    height=512,
)
# a double sphere lens on the T265's 848 x 800 image (its image circle holds the whole image)
T265_SIZED = DoubleSphere(fx=250.0, fy=250.2, cx=424.3, cy=400.1, xi=-0.2, alpha=0.57, width=848, height=800)


def paper_project(points, fx, fy, cx, cy, xi, alpha):
    """Eqs. (40)-(45) of the paper, step by step: two unit spheres, then a shifted pinhole."""
    out = []
    for x, y, z in points:
        d1 = np.sqrt(x**2 + y**2 + z**2)
        zeta = xi * d1 + z
        d2 = np.sqrt(x**2 + y**2 + zeta**2)
        w1 = alpha / (1 - alpha) if alpha <= 0.5 else (1 - alpha) / alpha
        w2 = (w1 + xi) / np.sqrt(2 * w1 * xi + xi**2 + 1)
        if not z > -w2 * d1:
            out.append((np.nan, np.nan))
            continue
        denominator = alpha * d2 + (1 - alpha) * zeta
        out.append((fx * x / denominator + cx, fy * y / denominator + cy))
    return np.array(out)


def paper_unproject(pixels, fx, fy, cx, cy, xi, alpha):
    """Eqs. (46)-(47): the ray, not normalised, and NaN outside r^2 <= 1 / (2 alpha - 1)."""
    out = []
    for u, v in pixels:
        mx, my = (u - cx) / fx, (v - cy) / fy
        r2 = mx**2 + my**2
        if alpha > 0.5 and r2 > 1 / (2 * alpha - 1):
            out.append((np.nan,) * 3)
            continue
        mz = (1 - alpha**2 * r2) / (alpha * np.sqrt(1 - (2 * alpha - 1) * r2) + 1 - alpha)
        factor = (mz * xi + np.sqrt(mz**2 + (1 - xi**2) * r2)) / (mz**2 + r2)
        out.append((factor * mx, factor * my, factor * mz - xi))
    return np.array(out)


def directions(rng, n, max_angle_deg):
    theta = np.radians(max_angle_deg) * np.sqrt(rng.uniform(0, 1, n))
    phi = rng.uniform(-np.pi, np.pi, n)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


@pytest.mark.parametrize("camera", [TUMVI, T265_SIZED], ids=["tumvi", "t265-sized"])
def test_projection_and_unprojection_equal_the_papers_formulas(camera):
    rng = np.random.default_rng(0)
    points = directions(rng, 3_000, 150.0) * rng.uniform(0.05, 20.0, (3_000, 1))
    uv, valid = camera.project(points)
    expected = paper_project(points, *camera.params)
    np.testing.assert_array_equal(valid, np.isfinite(expected[:, 0]))
    assert 0 < valid.sum() < len(points)
    np.testing.assert_allclose(uv[valid], expected[valid], rtol=1e-13)
    pixels = camera.pixel_grid()[::16, ::16].reshape(-1, 2)
    rays, valid = camera.unproject(pixels)
    expected = paper_unproject(pixels, *camera.params)
    np.testing.assert_array_equal(valid, np.isfinite(expected[:, 0]))
    expected = expected[valid] / np.linalg.norm(expected[valid], axis=-1, keepdims=True)
    np.testing.assert_allclose(rays[valid], expected, atol=1e-13)


def test_unproject_project_round_trip_over_the_whole_t265_sized_image():
    pixels = T265_SIZED.pixel_grid()
    rays, valid_rays = T265_SIZED.unproject(pixels)
    back, valid_back = T265_SIZED.project(rays)
    assert valid_rays.all() and valid_back.all()
    np.testing.assert_allclose(np.linalg.norm(rays, axis=-1), 1.0, atol=1e-12)
    assert np.max(np.abs(back - pixels)) < 1e-6


def test_project_unproject_round_trip_on_valid_points():
    rng = np.random.default_rng(1)
    rays = directions(rng, 20_000, 179.0)
    uv, valid = TUMVI.project(rays * rng.uniform(0.05, 20.0, (20_000, 1)))
    back, valid_back = TUMVI.unproject(uv[valid])
    assert valid_back.all() and 0.3 < valid.mean() < 1.0
    np.testing.assert_allclose(back, rays[valid], atol=1e-9)


@pytest.mark.parametrize("alpha", [0.3, 0.5, 0.6])
def test_xi_zero_is_the_eucm_with_beta_one(alpha):
    ds = DoubleSphere(300.0, 301.0, 320.0, 240.0, 0.0, alpha, 640, 480)
    eucm = EUCM(300.0, 301.0, 320.0, 240.0, alpha, 1.0, 640, 480)
    points = directions(np.random.default_rng(2), 2_000, 170.0)
    np.testing.assert_allclose(ds.project(points)[0], eucm.project(points)[0], rtol=1e-13, equal_nan=True)


def test_bad_points_and_pixels_give_nan_and_a_false_mask():
    uv, valid = TUMVI.project([[0.0, 0.0, 1.0], [np.nan, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, 0.0, 0.0]])
    np.testing.assert_array_equal(valid, [True, False, False, False])
    assert np.isnan(uv[1:]).all()
    rays, valid = TUMVI.unproject([[np.nan, 3.0], [1e4, 0.0]])
    assert not valid.any() and np.isnan(rays).all()


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"fy": -1.0}, "fy must be > 0"),
        ({"alpha": 1.5}, r"alpha must lie in \[0, 1\]"),
        ({"xi": 1.2}, r"xi must lie in \[-1, 1\]"),
        ({"xi": np.inf}, "xi must be a finite number"),
    ],
)
def test_invalid_parameters_raise_naming_them(change, message):
    params = dict(zip(DoubleSphere.PARAMETER_NAMES, TUMVI.params, strict=True)) | {"width": 512, "height": 512}
    with pytest.raises(ValueError, match=message):
        DoubleSphere(**(params | change))
