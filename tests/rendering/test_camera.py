"""Camera: the world-to-pixel mapping and the views it builds."""

import numpy as np
import pytest

from box_toss_env.rendering import Camera


def test_world_to_pixel_puts_centre_mid_image_and_y_up():
    camera = Camera(center_x=2.0, center_y=1.0, pixels_per_metre=50.0, width_px=200, height_px=100)
    np.testing.assert_allclose(camera.world_to_pixel([2.0, 1.0]), [100.0, 50.0])
    # one metre right is 50 px right; one metre up is 50 px *up* (smaller row)
    np.testing.assert_allclose(camera.world_to_pixel([[3.0, 1.0], [2.0, 2.0]]), [[150.0, 50.0], [100.0, 0.0]])


def test_pixel_to_world_inverts_world_to_pixel():
    camera = Camera(center_x=-0.3, center_y=0.7, pixels_per_metre=37.5, width_px=321, height_px=123)
    points = np.random.default_rng(0).normal(size=(10, 2))
    np.testing.assert_allclose(camera.pixel_to_world(camera.world_to_pixel(points)), points, atol=1e-12)


def test_pixel_index_is_row_column_of_containing_pixel():
    camera = Camera(center_x=0.0, center_y=0.0, pixels_per_metre=10.0, width_px=100, height_px=60)
    # (0.26, 0.26) m -> column 52.6, row 27.4
    assert camera.pixel_index([0.26, 0.26]) == (27, 52)


@pytest.mark.parametrize(("width_px", "height_px"), [(600, 400), (200, 400), (640, 120)])
def test_from_view_contains_rectangle_with_uniform_scale(width_px, height_px):
    camera = Camera.from_view(-1.0, 7.0, -0.5, 3.5, width_px, height_px)
    x_min, x_max, y_min, y_max = camera.view_bounds
    assert x_min <= -1.0 + 1e-9 and x_max >= 7.0 - 1e-9
    assert y_min <= -0.5 + 1e-9 and y_max >= 3.5 - 1e-9
    # the rectangle fills the image along at least one axis
    assert np.isclose(x_max - x_min, 8.0) or np.isclose(y_max - y_min, 4.0)


def test_fit_points_keeps_points_floor_and_margin_in_view():
    points = np.array([[2.0, 1.5], [4.0, 2.5]])
    camera = Camera.fit_points(points, 300, 200, margin_m=0.25)
    x_min, x_max, y_min, y_max = camera.view_bounds
    assert x_min <= 2.0 - 0.25 and x_max >= 4.0 + 0.25
    assert y_min <= 0.0 - 0.25 and y_max >= 2.5 + 0.25


def test_fit_points_single_point_has_minimum_span():
    camera = Camera.fit_points([[1.0, 1.0]], 100, 100, margin_m=0.0, min_span_m=2.0, include_floor=False)
    x_min, x_max, _, _ = camera.view_bounds
    assert np.isclose(x_max - x_min, 2.0)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"pixels_per_metre": 0.0, "width_px": 10, "height_px": 10},
        {"pixels_per_metre": 1.0, "width_px": 0, "height_px": 10},
    ],
)
def test_invalid_camera_raises(kwargs):
    with pytest.raises(ValueError):
        Camera(center_x=0.0, center_y=0.0, **kwargs)


def test_empty_view_rectangle_raises():
    with pytest.raises(ValueError, match="empty view"):
        Camera.from_view(1.0, 1.0, 0.0, 1.0, 10, 10)
