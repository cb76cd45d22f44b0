"""A Scene of several boxes in pymunk and Box2D: the same boxes, material and layout as ours."""

import numpy as np
import pytest

from benchmarks.other_engines import ENGINES
from benchmarks.other_scenes import (
    SCENE_ENGINE_MODULES,
    SCENE_ENGINES,
    Box2D3Settings,
    Layout,
    UnsupportedScene,
    make_world,
    simulate_scene,
)
from box_toss_env.physics import Box, Scene
from reports.cases import toss_of


@pytest.fixture(params=list(SCENE_ENGINES))
def engine(request) -> str:
    pytest.importorskip(SCENE_ENGINE_MODULES[request.param])
    return request.param


def colliding(scene: Scene) -> Scene:
    """``scene`` with boxes that collide with one another."""
    return scene.replace(boxes_collide=True)


def box(x, y, **kw):
    return Box(length=0.4, width=0.2, mass=kw.pop("mass", 2.0), position=(x, y), **kw)


def test_a_one_box_scene_is_the_toss_of_other_engines(engine):
    """Built the same way as the single-box adapter: the same states, bit for bit."""
    if engine not in ENGINES:
        pytest.skip(f"{engine} has no single-box adapter in benchmarks.other_engines")
    scene = Scene(
        boxes=(box(0.1, 1.2, angle=0.3, velocity=(3.0, 2.0), spin=5.0),), dt=1 / 240, restitution=0.3, friction=0.5
    )
    run = simulate_scene(engine, scene, 240)
    toss = ENGINES[engine].simulate_toss(toss_of(scene), scene.dt, 240, record=True)
    assert run.states.shape == (241, 1, 6)
    np.testing.assert_array_equal(run.states[:, 0], toss.states)
    assert run.ns_per_body_step > 0


def test_boxes_that_do_not_collide_pass_through_each_other(engine):
    scene = Scene(boxes=(box(0.0, 0.1), box(0.0, 0.5)), dt=1 / 240, restitution=0.0, friction=0.5)
    final = simulate_scene(engine, scene, 480, record=False).final_state
    assert final[1, 1] == pytest.approx(0.1, abs=6e-3)  # on the floor, inside the other box


def test_a_stack_of_two_rests_and_records_every_box(engine):
    scene = colliding(Scene(boxes=(box(0.0, 0.1), box(0.0, 0.3)), dt=1 / 240, restitution=0.0, friction=0.5))
    run = simulate_scene(engine, scene, 480)
    assert run.states.shape == (481, 2, 6)
    np.testing.assert_allclose(run.states[0], scene.initial_state(), atol=1e-6)
    np.testing.assert_allclose(run.final_state[:, 1], [0.1, 0.3], atol=6e-3)  # Box2D: up to 5 mm of overlap
    assert np.abs(run.final_state[:, 3:]).max() < 1e-3


@pytest.mark.parametrize("restitution", [0.0, 0.5, 1.0])
def test_a_head_on_collision_in_flight_has_the_scene_restitution_and_keeps_momentum(engine, restitution):
    """Two boxes face to face in zero gravity, 3 m/s each way: they part at e times their approach speed."""
    scene = colliding(
        Scene(
            boxes=(box(-0.3, 5.0, velocity=(3.0, 0.0), mass=1.0), box(0.3, 5.0, velocity=(-3.0, 0.0))),
            dt=1 / 240,
            gravity=0.0,
            restitution=restitution,
            friction=0.5,
        )
    )
    final = simulate_scene(engine, scene, 48, record=False).final_state
    # Box2D v3 applies restitution once per step and then its soft contacts push the remaining overlap apart:
    # measured 0.07, 3.26 and 6.55 m/s of parting speed for e = 0, 0.5 and 1 (up to 9% fast)
    tolerance = 0.6 if engine == "box2d3" else 0.02
    assert final[1, 3] - final[0, 3] == pytest.approx(6.0 * restitution, abs=tolerance)
    assert 1.0 * final[0, 3] + 2.0 * final[1, 3] == pytest.approx(3.0 - 6.0, abs=1e-5)  # float32 in Box2D


def test_a_mixed_material_scene_that_the_engine_cannot_mix_is_refused(engine):
    scene = colliding(Scene(boxes=(box(0.0, 0.1, restitution=0.2), box(0.0, 0.3, restitution=0.8)), dt=1 / 240))
    with pytest.raises(UnsupportedScene, match=engine):
        simulate_scene(engine, scene, 1)


def test_box2d_refuses_boxes_thinner_than_its_skin():
    pytest.importorskip("Box2D")
    scene = Scene(boxes=(Box(length=0.4, width=0.015, position=(0.0, 1.0)),), dt=1 / 240)
    with pytest.raises(UnsupportedScene, match="b2_polygonRadius"):
        simulate_scene("box2d", scene, 1)


def test_a_box_sliding_on_a_box_stops_after_v0_squared_over_2_mu_g(engine):
    """The box-box pair gets the scene's friction (pymunk: sqrt(mu) on each shape multiplies back to mu)."""
    v0, mu = 1.0, 0.6
    scene = colliding(
        Scene(
            boxes=(Box(length=2.0, width=0.2, mass=20.0, position=(0.0, 0.1)), box(-0.5, 0.3, velocity=(v0, 0.0))),
            dt=1 / 240,
            restitution=0.0,
            friction=mu,
        )
    )
    final = simulate_scene(engine, scene, 240, record=False).final_state
    assert final[1, 0] + 0.5 == pytest.approx(v0**2 / (2 * mu * -scene.gravity), rel=0.03)
    assert abs(final[0, 0]) < 1e-3  # the bottom box holds on the floor


def test_a_layout_places_the_bodies_elsewhere_and_reads_them_back_in_our_frame(engine):
    """Box2D's many_pyramids in the other engines: a box on a second floor 5 m up stays there, read back at y = 0."""
    scene = colliding(Scene(boxes=(box(0.0, 0.1), box(10.0, 0.1)), dt=1 / 60, restitution=0.0, friction=0.5))
    layout = Layout(offsets=np.array([[0.0, 0.0], [-10.0, 5.0]]), floors=((0.0, -2.0, 2.0), (5.0, -2.0, 2.0)))
    world = make_world(engine, scene, layout=layout)
    world.advance(60)
    out = np.empty((2, 6))
    world.read_states(out)
    np.testing.assert_allclose(out[:, :2], [[0.0, 0.1], [10.0, 0.1]], atol=6e-3)


def test_place_teleports_a_body_and_wakes_it(engine):
    scene = Scene(boxes=(box(0.0, 0.1), box(3.0, 0.1)), dt=1 / 60, restitution=0.0, friction=0.5)
    world = make_world(engine, scene, sleep=True)
    world.advance(120)  # Box2D's bodies fall asleep after 0.5 s at rest
    world.place(1, (0.0, 2.0, 0.0, 3.0, 0.0, 0.0))
    assert not world.asleep()[1]
    world.advance(1)
    out = np.empty((2, 6))
    world.read_states(out)
    assert out[1, 0] == pytest.approx(3.0 / 60, abs=1e-3) and out[1, 3] == pytest.approx(3.0, abs=1e-3)


def test_box2d3_contact_tuning_is_applied_only_where_asked():
    """Softer contacts (5 Hz instead of 30) let a resting box sink deeper: the setting reaches the solver."""
    pytest.importorskip("pyb2d3")
    scene = Scene(boxes=(Box(length=0.4, width=0.2, mass=200.0, position=(0.0, 0.1)),), dt=1 / 60)
    depth = {}
    for hertz in (None, 5.0):
        world = make_world("box2d3", scene, settings=Box2D3Settings(contact_hertz=hertz))
        world.advance(60)
        out = np.empty((1, 6))
        world.read_states(out)
        depth[hertz] = 0.1 - out[0, 1]
    assert depth[5.0] > 2 * depth[None] > 0
    assert not Box2D3Settings().tuned and Box2D3Settings(push=1.0).contact() == (30.0, 10.0, 1.0)
