"""Straight lines unproject onto planes: exactly with the true model, measurably not with a wrong one."""

import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gpo.cameras import T265_LIKE
from gpo.cameras.files import load_basalt
from gpo.cameras.straightness import aprilgrid_lines, aprilgrid_tags, line_residuals_deg, plane_residuals_deg
from gpo.io import datasets


def test_rays_in_one_plane_have_zero_residual_and_a_tilted_ray_its_angle():
    in_plane = np.array([[1.0, 0.0, 1.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 2.0], [0.5, 0.0, -1.0]])
    rays = in_plane / np.linalg.norm(in_plane, axis=1, keepdims=True)
    np.testing.assert_allclose(plane_residuals_deg(rays), 0.0, atol=1e-12)
    with pytest.raises(ValueError, match="at least 3 rays"):
        plane_residuals_deg(rays[:2])


def test_lines_in_space_are_straight_only_through_the_true_model():
    """Lines of a grid in space, projected by the true camera: residual ~0 with it, clearly not with a wrong alpha."""
    rotation = Rotation.from_euler("xyz", [0.3, -0.5, 0.2])
    u, v = np.meshgrid(np.linspace(-0.4, 0.4, 9), np.linspace(-0.3, 0.3, 7))
    board = np.stack([u, v, np.zeros_like(u)], -1).reshape(-1, 3)
    grid = (rotation.apply(board) + np.array([0.0, 0.0, 0.35])).reshape(7, 9, 3)
    pixels, valid = T265_LIKE.project(grid)
    assert valid.all()
    lines = [*pixels, *pixels.transpose(1, 0, 2)]
    assert line_residuals_deg(T265_LIKE, lines).max() < 1e-9  # measured 3e-14 deg: rounding
    wrong = dataclasses.replace(T265_LIKE, alpha=0.5)
    assert np.sqrt(np.mean(line_residuals_deg(wrong, lines) ** 2)) > 0.2  # measured 0.45 deg


def test_real_tum_vi_aprilgrid_is_straight_through_basalts_eucm(fetch_or_skip):
    fetch_or_skip("camera-intrinsic-model-rs/data/tum_vi_with_chart.png")
    fetch_or_skip("basalt/data/tumvi_512_eucm_calib.json")
    tags = aprilgrid_tags(datasets.tumvi_chart_image())
    assert len(tags) >= 15 and set(tags) <= set(range(36))
    lines = aprilgrid_lines(tags, tag_cols=6)
    camera = load_basalt(datasets.tumvi_eucm_calibration())[0]
    eucm = np.sqrt(np.mean(line_residuals_deg(camera, lines) ** 2))
    pinhole = np.sqrt(np.mean(line_residuals_deg(dataclasses.replace(camera, alpha=0.0, beta=1.0), lines) ** 2))
    assert eucm < 0.3 and pinhole > 1.5 * eucm  # measured 0.21 deg, and 1.63 times that through a pinhole
