"""The pymunk, Box2D and MuJoCo adapters simulate the toss we specify, in our conventions."""

import dataclasses
import math

import numpy as np
import pytest

from benchmarks.other_engines import (
    ENGINES,
    STATE_FIELDS,
    Engine,
    MujocoEngine,
    Toss,
    main,
    missing_engines,
    mujoco_xml,
    restitution_damping_ratio,
    steps_for_duration,
)

DT = 1.0 / 240.0

# Resting height error allowed per engine [m]: pymunk keeps up to its collision slop (1 mm) of overlap,
# Box2D up to b2_linearSlop (5 mm); MuJoCo's soft contact sinks < 0.1 mm at rest but keeps a small
# limit-cycle vibration at this restitution.
REST_HEIGHT_TOL = {"pymunk": 2e-3, "box2d": 6e-3, "mujoco": 3e-3}
REST_SPEED_TOL = {"pymunk": 1e-3, "box2d": 1e-3, "mujoco": 0.1}
# Flat-drop restitution error allowed: exact for the impulse engines, approximate for MuJoCo's spring.
RESTITUTION_TOL = {"pymunk": 0.01, "box2d": 0.02, "mujoco": 0.08}


@pytest.fixture(params=list(ENGINES))
def engine(request) -> Engine:
    engine = ENGINES[request.param]
    pytest.importorskip(engine.module)
    return engine


def test_missing_engines_is_a_list_of_unavailable_names():
    missing = missing_engines()
    assert isinstance(missing, list)
    assert missing == [name for name, engine in ENGINES.items() if not engine.available()]


def test_an_engine_whose_package_is_absent_is_reported_missing():
    class Absent(MujocoEngine):
        name = "absent"
        package = "no-such-engine"
        module = "no_such_engine_module_xyz"

    absent = Absent()
    assert not absent.available()
    with pytest.raises(ImportError, match="no-such-engine"):
        absent.simulate_toss(Toss(), DT, 1)


def test_toss_rejects_unphysical_inputs():
    for bad in ({"mass": 0.0}, {"width": -0.1}, {"restitution": 1.5}, {"friction": -0.1}, {"y": math.nan}):
        with pytest.raises(ValueError):
            Toss(**bad)
    assert Toss().moment == pytest.approx(1.0 * (0.3**2 + 0.15**2) / 12)


def test_result_shapes_and_timing(engine):
    toss = Toss()
    n_steps = 24
    final = engine.simulate_toss(toss, DT, n_steps)
    assert final.engine == engine.name
    assert final.states is None
    assert final.final_state.shape == (len(STATE_FIELDS),)
    assert final.steps == n_steps
    assert final.wall_seconds > 0 and final.ns_per_step > 0

    recorded = engine.simulate_toss(toss, DT, n_steps, record=True)
    assert recorded.states.shape == (n_steps + 1, len(STATE_FIELDS))
    np.testing.assert_allclose(recorded.states[0], toss.initial_state(), rtol=1e-6, atol=1e-6)
    np.testing.assert_array_equal(recorded.states[-1], recorded.final_state)
    np.testing.assert_array_equal(recorded.final_state, final.final_state)  # fresh scene each call


@pytest.mark.parametrize("toss", [Toss(), Toss(length=0.5, width=0.2, mass=2.5), Toss(length=0.1, width=0.4)])
def test_mass_and_moment_are_as_specified(engine, toss):
    mass, moment = engine.mass_properties(toss)
    assert mass == pytest.approx(toss.mass, rel=1e-6)  # Box2D is float32
    assert moment == pytest.approx(toss.mass * (toss.length**2 + toss.width**2) / 12, rel=1e-6)


def test_free_flight_is_the_parabola_with_constant_spin(engine):
    """Semi-implicit Euler is off the parabola by |g| t dt / 2 in y; velocities and angle are exact."""
    toss = Toss(x=-1.0, y=10.0, angle=0.2, vx=1.5, vy=2.0, omega=1.0)
    duration = 0.5
    result = engine.simulate_toss(toss, DT, steps_for_duration(duration, DT), record=True)
    t = DT * np.arange(result.steps + 1)
    g = toss.gravity
    expected = np.column_stack(
        [
            toss.x + toss.vx * t,
            toss.y + toss.vy * t + 0.5 * g * t**2,
            toss.angle + toss.omega * t,
            np.full_like(t, toss.vx),
            toss.vy + g * t,
            np.full_like(t, toss.omega),
        ]
    )
    float32_slack = 1e-4  # Box2D stores positions and velocities in float32
    position_tol = 2 * abs(g) * t * DT + float32_slack
    error = np.abs(result.states - expected)
    assert np.all(error[:, 1] <= position_tol)
    assert np.all(error[:, [0, 2]] <= float32_slack)
    assert np.all(error[:, 3:] <= float32_slack)
    # counter-clockwise positive: a spin of +1 rad/s turns the box by +0.5 rad in 0.5 s
    assert result.final_state[2] - toss.angle == pytest.approx(0.5, abs=1e-4)


def test_tilted_box_tips_over_its_lower_left_corner(engine):
    """Geometric meaning of the angle: at +0.3 rad (counter-clockwise) the lower-left corner touches first.

    The box pivots on that corner, at x = -L/2 cos(a) + W/2 sin(a), and falls clockwise onto its face, so
    its centre ends at that x + L/2 > 0; with the opposite angle convention it would end at x < 0.
    """
    angle, L, W = 0.3, 0.3, 0.15
    lowest = L / 2 * math.sin(angle) + W / 2 * math.cos(angle)
    toss = Toss(
        length=L,
        width=W,
        x=0.0,
        y=lowest + 1e-3,
        angle=angle,
        vx=0.0,
        vy=0.0,
        omega=0.0,
        restitution=0.0,
        friction=1.0,
    )
    final = engine.simulate_toss(toss, DT, steps_for_duration(1.5, DT)).final_state
    pivot_x = -L / 2 * math.cos(angle) + W / 2 * math.sin(angle)
    assert final[0] == pytest.approx(pivot_x + L / 2, abs=5e-3)
    assert final[2] == pytest.approx(0.0, abs=0.02)


def test_box_dropped_flat_rests_at_half_its_width(engine):
    toss = Toss(x=0.0, y=0.3, angle=0.0, vx=0.0, vy=0.0, omega=0.0)
    result = engine.simulate_toss(toss, DT, steps_for_duration(2.0, DT))
    x, y, angle, vx, vy, omega = result.final_state
    assert y == pytest.approx(toss.width / 2, abs=REST_HEIGHT_TOL[engine.name])
    assert abs(x) < 1e-3 and abs(angle) < 1e-3
    assert max(abs(vx), abs(vy), abs(omega)) < REST_SPEED_TOL[engine.name]


@pytest.mark.parametrize("restitution", [0.3, 0.6, 0.9])
def test_flat_drop_rebounds_with_the_restitution(engine, restitution):
    """Impact at 3 m/s (above Box2D's 1 m/s restitution threshold); rebound speed / impact speed = e."""
    toss = Toss(x=0.0, y=0.085, angle=0.0, vx=0.0, vy=-3.0, omega=0.0, restitution=restitution)
    vy = engine.simulate_toss(toss, DT, steps_for_duration(0.15, DT), record=True).states[:, 4]
    assert vy.max() / -vy.min() == pytest.approx(restitution, abs=RESTITUTION_TOL[engine.name])


@pytest.mark.parametrize("restitution", [0.0, 0.1, 0.3, 0.6, 0.9, 1.0])
def test_mujoco_damping_ratio_gives_the_oscillator_restitution(restitution):
    zeta = restitution_damping_ratio(restitution)
    assert 0.0 <= zeta <= 1.0
    if restitution > 0:
        assert math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2)) == pytest.approx(restitution)


@pytest.mark.parametrize("angle", [0.0, 0.3, -1.2, 2.5])
def test_mujoco_axes_map_our_plane_to_its_x_z_plane(angle):
    """qpos = [x, y, angle] puts the box's own x axis at (cos a, 0, sin a) and its centre at (x, 0, y)."""
    mujoco = pytest.importorskip("mujoco")
    toss = Toss(x=0.7, y=1.1, angle=angle)
    model = mujoco.MjModel.from_xml_string(mujoco_xml(toss, DT))
    data = mujoco.MjData(model)
    data.qpos[:] = toss.initial_state()[:3]
    mujoco.mj_kinematics(model, data)
    box = data.geom("box")
    rotation = box.xmat.reshape(3, 3)  # columns: the box's axes in world coordinates
    np.testing.assert_allclose(box.xpos, [toss.x, 0.0, toss.y], atol=1e-12)
    np.testing.assert_allclose(rotation[:, 0], [math.cos(angle), 0.0, math.sin(angle)], atol=1e-12)
    np.testing.assert_allclose(rotation[:, 2], [-math.sin(angle), 0.0, math.cos(angle)], atol=1e-12)
    np.testing.assert_allclose(
        model.geom("box").size, [toss.length / 2, min(toss.length, toss.width) / 2, toss.width / 2]
    )


def test_box2d_clamps_translation_per_step():
    """Documented limit: b2_maxTranslation = 2 m per step, so 1000 m/s at dt = 1/240 moves only 2 m."""
    Box2D = pytest.importorskip("Box2D")
    toss = Toss(x=0.0, y=10.0, vx=1000.0, vy=0.0, omega=0.0, gravity=0.0)
    final = ENGINES["box2d"].simulate_toss(toss, DT, 1).final_state
    assert final[0] == pytest.approx(Box2D.b2_maxTranslation, rel=1e-6)
    assert 1000.0 * DT > Box2D.b2_maxTranslation


def test_cli_prints_each_available_engine_and_the_missing_ones(capsys):
    assert main(["--duration", "0.05", "--repeat", "1"]) == 0
    out = capsys.readouterr().out
    assert "ns/step" in out and "missing:" in out
    rows = {line.split()[0] for line in out.splitlines() if line.strip()}
    missing_line = out.split("missing:")[1]
    for name, engine in ENGINES.items():
        assert (name in rows) if engine.available() else (name in missing_line)


def test_toss_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        Toss().mass = 2.0
