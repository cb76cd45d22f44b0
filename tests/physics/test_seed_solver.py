"""The seed solver is the reference text's scheme, exactly."""

import numpy as np
import pytest
import seed_reference
from seed_reference import ReferenceBody, reference_step

from box_toss_env.physics import Box, NonFiniteStateError, Scene, layout, scenes, simulate


def run_reference(scene: Scene, steps: int) -> np.ndarray:
    bodies = [ReferenceBody(b.length, b.width, b.mass, *b.position, b.angle, *b.velocity, b.spin) for b in scene.boxes]
    states = np.empty((steps + 1, len(bodies), 6))
    states[0] = [body.state() for body in bodies]
    for n in range(1, steps + 1):
        for body in bodies:
            reference_step(
                body,
                scene.dt,
                scene.gravity,
                scene.penalty_stiffness,
                scene.restitution,
                scene.friction,
                scene.use_impulses,
                scene.use_penalty,
            )
        states[n] = [body.state() for body in bodies]
    return states


TOSSED = Box(length=2.0, width=1.0, mass=1.0, position=(0.0, 3.0), angle=0.7, velocity=(2.0, 1.0), spin=3.0)


@pytest.mark.parametrize(
    "use_impulses, use_penalty, friction",
    [
        (True, True, 0.02),
        (True, True, 0.0),
        (True, False, 0.3),
        (False, True, 0.3),
        (False, True, 0.0),
    ],
)
def test_one_box_agrees_with_the_text_over_thousands_of_steps(use_impulses, use_penalty, friction):
    scene = Scene(boxes=(TOSSED,), solver="seed", use_impulses=use_impulses, use_penalty=use_penalty, friction=friction)
    steps = 3000
    kernel = simulate(scene, steps=steps, record=True).trajectory.state
    reference = run_reference(scene, steps)
    assert kernel.shape == reference.shape
    np.testing.assert_allclose(kernel, reference, rtol=0, atol=1e-12)


def test_seed_demo_agrees_with_the_text_for_five_boxes():
    scene = scenes.seed_demo(seed=3)
    steps = 2000
    kernel = simulate(scene, steps=steps, record=True).trajectory.state
    np.testing.assert_allclose(kernel, run_reference(scene, steps), rtol=0, atol=1e-12)


DEMO_CORNER_ORDER = [(-1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (1.0, -1.0)]  # (-L/2, -W/2), (-L/2, +W/2), ...


def test_corners_are_visited_in_the_demos_order(monkeypatch):
    """The demo visits (-L/2, -W/2), (-L/2, +W/2), (+L/2, +W/2), (+L/2, -W/2). Corners below the floor
    are resolved one after another, so a box landing upside down on its two +W/2 corners in one step
    (visited -L/2 first in the demo's order, +L/2 first counter-clockwise) ends elsewhere in the other
    order; the kernel follows the demo's."""
    assert list(zip(layout.SEED_SIGN_X, layout.SEED_SIGN_Y, strict=True)) == DEMO_CORNER_ORDER
    assert list(seed_reference.CORNERS) == DEMO_CORNER_ORDER
    upside_down = Box(length=2.0, width=1.0, position=(0.0, 1.5), angle=np.pi, velocity=(1.0, 0.0))
    scene = Scene(boxes=(upside_down,), solver="seed", friction=0.3)
    kernel = simulate(scene, steps=400).final_state[0]
    np.testing.assert_allclose(kernel, run_reference(scene, 400)[-1, 0], rtol=0, atol=1e-12)
    monkeypatch.setattr(seed_reference, "CORNERS", ((-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)))
    counter_clockwise = run_reference(scene, 400)[-1, 0]
    assert np.abs(kernel - counter_clockwise).max() > 0.1  # the order matters (0.94 m), and it is the demo's


def test_a_resting_box_creeps_with_friction_not_restitution():
    """The seed scheme's creep of a resting box (10 s at dt 0.005 s) is driven by friction: none with mu = 0
    (whatever e), centimetres with mu = 0.5 (with e = 0 too)."""

    def creep(restitution, friction):
        scene = scenes.resting(solver="seed", restitution=restitution, friction=friction)
        return abs(simulate(scene, duration=10.0).final_state[0, layout.X])

    assert creep(0.5, 0.0) == 0.0 and creep(0.0, 0.0) == 0.0
    assert 0.1 < creep(0.5, 0.5) < 0.2 and 0.1 < creep(0.0, 0.5) < 0.2


def test_seed_demo_has_the_panel_defaults():
    scene = scenes.seed_demo()
    assert scene.solver == "seed" and scene.n_bodies == 5
    assert (scene.dt, scene.gravity, scene.penalty_stiffness, scene.restitution, scene.friction) == (
        0.005,
        -9.81,
        100.0,
        0.5,
        0.02,
    )
    assert scene.use_impulses and scene.use_penalty
    xs = [box.position[0] for box in scene.boxes]
    assert xs == [-5.0, -2.0, 1.0, 4.0, 7.0]
    assert all(0.0 <= box.angle < np.pi and box.position[1] == 5.0 for box in scene.boxes)


def test_free_flight_height_error_is_exactly_g_t_dt_over_2():
    """Symplectic Euler: y_n = y0 + v0 t + g t^2/2 + g t dt/2 with t = n dt."""
    scene = scenes.free_flight(solver="seed", dt=0.01)
    box = scene.boxes[0]
    trajectory = simulate(scene, steps=100, record=True).trajectory
    t = trajectory.time
    exact = box.position[1] + box.velocity[1] * t + 0.5 * scene.gravity * t**2
    np.testing.assert_allclose(
        trajectory.position[:, 0, 1] - exact, scene.gravity * t * scene.dt / 2, rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(trajectory.angle[:, 0], box.angle + box.spin * t, rtol=0, atol=1e-12)


def test_explicit_penalty_beyond_its_stability_limit_launches_the_box():
    """k = 1e5 N/m on a resting 1 kg box at dt = 0.005 s: omega dt = sqrt(2k/m) dt = 2.2 > 2, so the
    explicit penalty spring gains energy every step in contact and throws the box metres up."""
    trajectory = simulate(scenes.stiff(solver="seed"), duration=5.0, record=True).trajectory
    assert trajectory.position[:, 0, 1].max() > 10.0
    calm = simulate(scenes.stiff(solver="seed", penalty_stiffness=1e4), duration=5.0, record=True).trajectory
    assert calm.position[:, 0, 1].max() < 1.0


def test_a_state_that_turns_non_finite_is_reported_with_its_body_and_step():
    high = Box(position=(0.0, 1e3))
    sunk = Box(position=(5.0, 0.4))
    scene = Scene(boxes=(high, sunk), solver="seed", penalty_stiffness=1e300, friction=0.5)
    with pytest.raises(NonFiniteStateError) as caught:
        simulate(scene, steps=100)
    assert caught.value.body == 1 and 1 <= caught.value.step <= 100
    assert "body 1" in str(caught.value) and f"step {caught.value.step}" in str(caught.value)
