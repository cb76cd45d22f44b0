"""Camera: the world-to-pixel mapping and the views it builds."""

import numpy as np
import pytest

from box_toss_env.rendering import Camera, bounds_of_boxes, follow_bounds, union_bounds


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


def test_from_view_with_padding_fits_the_rectangle_into_the_padded_region():
    padding = (10, 30, 40, 20)  # left, right, top, bottom [px]
    camera = Camera.from_view(-1.0, 7.0, 0.0, 3.0, 600, 400, padding_px=padding)
    corners = camera.world_to_pixel(np.array([[-1.0, 0.0], [7.0, 3.0]]))
    assert corners[:, 0].min() >= 10 - 1e-9 and corners[:, 0].max() <= 600 - 30 + 1e-9
    assert corners[:, 1].min() >= 40 - 1e-9 and corners[:, 1].max() <= 400 - 20 + 1e-9
    # the rectangle fills the padded region along x (the tighter axis here) and is centred in it along y
    assert corners[0, 0] == pytest.approx(10) and corners[1, 0] == pytest.approx(570)
    assert 0.5 * (corners[0, 1] + corners[1, 1]) == pytest.approx(40 + 0.5 * (400 - 60))
    with pytest.raises(ValueError, match="padding"):
        Camera.from_view(0.0, 1.0, 0.0, 1.0, 100, 100, padding_px=(60, 40, 0, 0))


def test_bounds_and_their_union():
    corners = np.array([[[0.0, 1.0], [2.0, 1.0], [2.0, 3.0], [0.0, 3.0]]])
    np.testing.assert_array_equal(bounds_of_boxes(corners), [[0.0, 2.0, 1.0, 3.0]])
    np.testing.assert_array_equal(
        union_bounds([[0.0, 2.0, 1.0, 3.0], [5.0, 6.0, -1.0, 0.0]], [1.0, 1.5, 0.0, 4.0]),
        [[0.0, 2.0, 0.0, 4.0], [1.0, 6.0, -1.0, 4.0]],
    )


@pytest.mark.parametrize("radius", [0, 1, 7, 15])
def test_follow_bounds_contain_every_frame_and_move_gradually(radius):
    rng = np.random.default_rng(radius)
    centres = np.cumsum(rng.normal(scale=0.3, size=(200, 2)), axis=0)
    centres[120] += 8.0  # a jump: the view must still hold it, opening before it comes
    bounds = np.column_stack([centres[:, 0] - 0.2, centres[:, 0] + 0.2, centres[:, 1] - 0.1, centres[:, 1] + 0.1])
    followed = follow_bounds(bounds, radius)
    assert followed.shape == bounds.shape
    assert np.all(followed[:, [0, 2]] <= bounds[:, [0, 2]] + 1e-12)
    assert np.all(followed[:, [1, 3]] >= bounds[:, [1, 3]] - 1e-12)
    if radius:
        # away from the ends (shorter windows), an edge moves at most 1 / (2 radius + 1) of the range of
        # that edge in the input per frame: a jump is spread over 2 radius + 1 frames
        input_range = bounds.max(axis=0) - bounds.min(axis=0)
        steps = np.abs(np.diff(followed[radius:-radius], axis=0)).max(axis=0)
        assert np.all(steps <= input_range / (2 * radius + 1) + 1e-9)
    else:
        np.testing.assert_array_equal(followed, bounds)
