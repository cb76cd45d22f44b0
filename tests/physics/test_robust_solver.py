"""The robust solver against closed-form answers, conservation laws and symmetry."""

import math

import numpy as np
import pytest
from physics_checks import energy, lowest_corner_height

from box_toss_env.physics import Box, Scene, scenes, simulate


def test_free_flight_is_the_closed_form_parabola():
    scene = scenes.free_flight()
    box = scene.boxes[0]
    trajectory = simulate(scene, duration=1.0, record=True).trajectory
    t = trajectory.time
    np.testing.assert_allclose(trajectory.position[:, 0, 0], box.position[0] + box.velocity[0] * t, atol=1e-9)
    np.testing.assert_allclose(
        trajectory.position[:, 0, 1], box.position[1] + box.velocity[1] * t + 0.5 * scene.gravity * t**2, atol=1e-9
    )
    np.testing.assert_allclose(trajectory.angle[:, 0], box.angle + box.spin * t, atol=1e-9)
    np.testing.assert_allclose(trajectory.velocity[:, 0, 1], box.velocity[1] + scene.gravity * t, atol=1e-9)


@pytest.mark.parametrize("angle, spin, restitution", [(0.4, 0.0, 0.5), (-0.9, 2.0, 0.0), (2.5, -1.0, 1.0)])
def test_single_frictionless_corner_impact_follows_newtons_impact_law(angle, spin, restitution):
    """Zero gravity, so the box reaches the floor with its initial velocity; then the impulse
    lam = -(1 + e) u_n / (1/m + rx^2 / I) at the touching corner gives v+ and omega+."""
    scene = scenes.corner_impact(angle=angle, velocity=(0.3, -3.0), spin=spin, restitution=restitution)
    box = scene.boxes[0]
    result = simulate(scene, duration=0.01, record=True)
    t_contact = result.first_contact_time[0]
    theta = box.angle + box.spin * t_contact
    corners = [(sx * box.length / 2, sy * box.width / 2) for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    offsets = [
        (math.cos(theta) * bx - math.sin(theta) * by, math.sin(theta) * bx + math.cos(theta) * by) for bx, by in corners
    ]
    rx, ry = min(offsets, key=lambda r: r[1])
    assert box.position[1] + box.velocity[1] * t_contact + ry == pytest.approx(0.0, abs=1e-9)
    u_n = box.velocity[1] + box.spin * rx
    impulse = -(1 + restitution) * u_n / (1 / box.mass + rx * rx / box.inertia)
    expected = (box.velocity[0], box.velocity[1] + impulse / box.mass, box.spin + rx * impulse / box.inertia)
    assert result.n_impacts[0] == 1
    np.testing.assert_allclose(result.final_state[0, 3:], expected, rtol=0, atol=1e-9)


@pytest.mark.parametrize("restitution", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("angle, length, width", [(0.0, 2.0, 1.0), (math.pi, 2.0, 1.0), (math.pi / 2, 1.0, 2.0)])
def test_flat_drop_rebounds_to_e_squared_h_without_spin(restitution, angle, length, width):
    """The same level drop whichever corners are the bottom ones: apex e^2 h, no spin."""
    height = 1.0
    box = Box(length=length, width=width, mass=1.0, position=(0.0, height + 0.5), angle=angle)
    scene = Scene(boxes=(box,), restitution=restitution, friction=0.3, dt=1 / 512)
    result = simulate(scene, duration=2 * math.sqrt(2 * height / 9.81) + 0.05, record=True)
    trajectory = result.trajectory
    bottom = lowest_corner_height(scene, trajectory)
    after_impact = trajectory.time > result.first_contact_time[0] + 0.01
    apex = bottom[after_impact].max()
    assert apex == pytest.approx(restitution**2 * height, rel=0.01, abs=1e-3)
    assert np.abs(trajectory.spin[:, 0]).max() < 1e-6


def test_sliding_box_stops_after_v_squared_over_2_mu_g_and_never_reverses():
    speed, friction = 2.0, 0.3
    scene = scenes.slide(speed=speed, friction=friction)
    trajectory = simulate(scene, duration=1.5, record=True).trajectory
    distance = trajectory.position[-1, 0, 0] - trajectory.position[0, 0, 0]
    assert distance == pytest.approx(speed**2 / (2 * friction * -scene.gravity), rel=0.01)
    assert trajectory.velocity[-1, 0, 0] == pytest.approx(0.0, abs=1e-12)
    assert trajectory.velocity[:, 0, 0].min() >= -1e-12  # rounding of the friction torque, no reversal
    assert np.diff(trajectory.position[:, 0, 0]).min() >= -1e-14


def test_resting_box_does_not_creep_or_gain_energy():
    scene = scenes.resting(restitution=0.5, friction=0.02)
    trajectory = simulate(scene, duration=10.0, record=True).trajectory
    drift = np.abs(trajectory.position[:, 0] - trajectory.position[0, 0]).max()
    assert drift < 1e-3
    e = energy(scene, trajectory)
    assert e.max() <= e[0] + 1e-9


def test_elastic_bouncing_keeps_its_energy_for_20_seconds():
    scene = scenes.bouncing(restitution=1.0, dt=1 / 256)
    trajectory = simulate(scene, duration=20.0, record=True).trajectory
    e = energy(scene, trajectory)
    assert np.abs(e / e[0] - 1).max() < 0.01


def mirrored(scene: Scene) -> Scene:
    boxes = tuple(
        Box(
            length=b.length,
            width=b.width,
            mass=b.mass,
            position=(-b.position[0], b.position[1]),
            angle=-b.angle,
            velocity=(-b.velocity[0], b.velocity[1]),
            spin=-b.spin,
        )
        for b in scene.boxes
    )
    return scene.replace(boxes=boxes)


@pytest.mark.parametrize("solver", ["robust", "seed"])
def test_mirror_image_of_a_throw_is_the_mirrored_throw(solver):
    scene = scenes.toss(solver=solver, restitution=0.0, dt=1 / 512)
    if solver == "seed":
        scene = scene.replace(penalty_stiffness=2e3)
    original = simulate(scene, duration=1.2, record=True).trajectory.state[:, 0]
    image = simulate(mirrored(scene), duration=1.2, record=True).trajectory.state[:, 0]
    flip = np.array([-1.0, 1.0, -1.0, -1.0, 1.0, -1.0])
    np.testing.assert_allclose(image * flip, original, rtol=0, atol=1e-6)


@pytest.mark.parametrize("solver", ["robust", "seed"])
def test_runs_are_bit_identical_and_independent_of_threads(solver):
    scene = scenes.seed_demo(solver=solver, seed=1)
    first = simulate(scene, duration=3.0, record=True)
    second = simulate(scene, duration=3.0, record=True)
    one_thread = simulate(scene, duration=3.0, record=True, threads=1)
    np.testing.assert_array_equal(first.trajectory.state, second.trajectory.state)
    np.testing.assert_array_equal(first.trajectory.state, one_thread.trajectory.state)
    separately = [simulate(scene.replace(boxes=(box,)), duration=3.0).final_state[0] for box in scene.boxes]
    np.testing.assert_array_equal(first.final_state, np.array(separately))


def test_a_throw_comes_to_rest_lying_on_a_face():
    result = simulate(scenes.toss(), duration=10.0, until_rest=True)
    assert result.at_rest[0] and result.rest_time[0] < 10.0
    x, y, angle, vx, vy, spin = result.final_state[0]
    assert (vx, vy, spin) == (0.0, 0.0, 0.0)
    assert y == pytest.approx(0.1, abs=1e-4) or y == pytest.approx(0.2, abs=1e-4)
    assert math.remainder(angle, math.pi / 2) == pytest.approx(0.0, abs=2e-3)


@pytest.mark.parametrize("stiffness", [1e2, 1e9])
@pytest.mark.parametrize("dt", [2.0**-5, 2.0**-14])
def test_box_started_inside_the_floor_is_pushed_out_without_launch(stiffness, dt):
    """The penalty correction removes the depth at a rate set by the stiffness, not by the step."""
    box = Box(length=2.0, width=1.0, mass=1.0, position=(0.0, 0.5 - 0.25))
    scene = Scene(boxes=(box,), penalty_stiffness=stiffness, dt=dt)
    trajectory = simulate(scene, duration=3.0, record=True).trajectory
    assert trajectory.position[-1, 0, 1] == pytest.approx(0.5, abs=1e-3)
    assert trajectory.position[:, 0, 1].max() <= 0.5 + 1e-6
    assert np.abs(trajectory.velocity[:, 0]).max() < 1e-9


@pytest.mark.parametrize("restitution, friction", [(1.0, 1.0), (0.5, 0.3), (1.0, 0.0)])
def test_impacts_with_friction_never_create_energy(restitution, friction):
    """A spinning square box bouncing with e = 1 and mu = 1: Newton's restitution law with friction
    would gain energy here (5% at the first impact); the robust solver's impacts never do."""
    box = Box(length=1.0, width=1.0, mass=1.0, position=(0.0, 0.5 * math.sqrt(2.0)), spin=1.0)
    scene = Scene(boxes=(box,), restitution=restitution, friction=friction, penalty_stiffness=100.0, dt=1 / 32)
    trajectory = simulate(scene, duration=2.0, record=True).trajectory
    e = energy(scene, trajectory)
    assert e.max() <= e[0] * (1 + 1e-12)


@pytest.mark.parametrize("speed", [5.0, 50.0, 200.0])
def test_fast_impacts_do_not_tunnel_and_e0_does_not_rebound(speed):
    box = Box(length=0.4, width=0.2, mass=2.0, position=(0.0, 3.0), angle=0.3, velocity=(0.0, -speed))
    scene = Scene(boxes=(box,), restitution=0.0, friction=0.5, penalty_stiffness=1e5, dt=1 / 64)
    result = simulate(scene, duration=2.0, record=True)
    assert lowest_corner_height(scene, result.trajectory).min() > -1e-3
    assert result.trajectory.velocity[:, 0, 1].max() < 0.1 * speed
