"""ViewerController: the seed demo's controls on live scenes, without a window."""

import math

import numpy as np
import pytest

from box_toss_env.physics import Box, Scene, Simulator, layout, make_settings, scenes, simulate
from box_toss_env.rendering import box_vertices
from box_toss_env.viewer import PARAMETERS, ROWS, STEPS_PER_FRAME, StepTimer, ViewerController
from box_toss_env.viewer.controller import PARAMETER_BY_NAME, TIMING_WINDOW_STEPS, view_points


@pytest.fixture
def demo() -> ViewerController:
    return ViewerController(scenes.seed_demo())


def run_frames(controller: ViewerController, n: int) -> None:
    for _ in range(n):
        controller.advance_frame()


def test_opens_the_seed_demo_with_its_panel_and_read_outs(demo):
    assert len(demo.lanes) == 1 and demo.lanes[0].solver == "seed"
    assert [demo.row_value(row) for row in ROWS] == [
        "0.005 s",
        "-9.81 m/s^2",
        "100 N/m",
        "0.5",
        "0.02",
        "on",
        "on",
        "off",
        "seed",
    ]
    assert demo.readouts(0) == ["seed solver", "0.00 s", "-- ms / step", "5 bodies"]
    np.testing.assert_array_equal(demo.lanes[0].state, scenes.seed_demo().initial_state())


def test_a_frame_is_eight_steps_of_the_engine(demo):
    run_frames(demo, 10)
    lane = demo.lanes[0]
    assert STEPS_PER_FRAME == 8
    assert lane.steps == 80 and lane.sim_time == pytest.approx(80 * 0.005)
    np.testing.assert_array_equal(lane.state, simulate(scenes.seed_demo(), steps=80).final_state)
    assert demo.readouts(0)[1] == "0.40 s"


def test_a_pile_stepped_frame_by_frame_is_the_pile_stepped_at_once():
    # the lane carries the contacts' impulses from frame to frame (Simulator.run's warm_start)
    scene = scenes.pile(12, solver="robust")
    controller = ViewerController(scene)
    run_frames(controller, 10)
    lane = controller.lanes[0]
    assert lane.warm_start is not None and lane.steps == 80
    np.testing.assert_array_equal(lane.state, simulate(scene, steps=80).final_state)


def test_pause_stops_stepping_and_single_step_still_steps(demo):
    demo.toggle_pause()
    before = demo.lanes[0].state.copy()
    run_frames(demo, 3)
    np.testing.assert_array_equal(demo.lanes[0].state, before)
    assert "paused" in demo.readouts(0)
    demo.advance_frame(force=True)
    assert demo.lanes[0].steps == STEPS_PER_FRAME
    demo.toggle_pause()
    run_frames(demo, 1)
    assert demo.lanes[0].steps == 2 * STEPS_PER_FRAME


def test_restart_goes_back_to_the_initial_state_with_the_current_parameters(demo):
    demo.set_parameter("restitution", 0.2)
    run_frames(demo, 20)
    demo.toggle_pause()
    demo.restart()
    lane = demo.lanes[0]
    np.testing.assert_array_equal(lane.state, scenes.seed_demo().initial_state())
    assert (lane.sim_time, lane.steps, demo.paused) == (0.0, 0, False)
    assert lane.params[0, layout.RESTITUTION] == 0.2


def test_parameter_changes_reach_the_kernel_arrays_and_keep_the_simulator(demo):
    lane = demo.lanes[0]
    simulator = lane.simulator
    changes = {"dt": 0.002, "gravity": -3.0, "penalty_stiffness": 500.0, "restitution": 0.9, "friction": 0.3}
    for name, value in changes.items():
        assert demo.set_parameter(name, value), demo.message
    assert lane.settings[layout.DT] == 0.002 and lane.settings[layout.GRAVITY] == -3.0
    assert lane.settings[layout.MAX_STEPS] == STEPS_PER_FRAME
    np.testing.assert_array_equal(lane.params[:, layout.STIFFNESS], 500.0)
    np.testing.assert_array_equal(lane.params[:, layout.RESTITUTION], 0.9)
    np.testing.assert_array_equal(lane.params[:, layout.FRICTION], 0.3)
    assert lane.simulator is simulator  # no compile-time flag changed
    run_frames(demo, 1)
    assert lane.sim_time == pytest.approx(STEPS_PER_FRAME * 0.002)


@pytest.mark.parametrize(
    ("change", "flag", "value"),
    [
        ({"friction": 0.0}, "use_friction", False),
        ({"penalty_stiffness": 0.0}, "use_penalty", False),
    ],
)
def test_a_change_of_compile_time_flags_rebuilds_the_simulator(demo, change, flag, value):
    before = demo.lanes[0].simulator
    ((name, number),) = change.items()
    assert demo.set_parameter(name, number)
    assert demo.lanes[0].simulator is not before
    assert getattr(demo.lanes[0].simulator.flags, flag) is value


@pytest.mark.parametrize(
    ("name", "value", "reason"),
    [
        ("restitution", 1.5, "restitution must be in [0, 1], got 1.5"),
        ("dt", 0.0, "dt must be in [1e-7, 1] s, got 0.0"),
        ("friction", "abc", "friction must be a number, got 'abc'"),
    ],
)
def test_an_invalid_value_is_shown_and_changes_nothing(demo, name, value, reason):
    scene = demo.scene
    assert not demo.set_parameter(name, value)
    assert reason in demo.message
    assert demo.scene is scene
    assert demo.set_parameter(name, 0.25)
    assert demo.message == ""


def test_arrow_keys_walk_each_parameter_along_its_ladder(demo):
    steps = {
        "dt": (0.004, 0.0075),
        "gravity": (-10.0, -9.0),
        "penalty_stiffness": (50.0, 200.0),
        "restitution": (0.45, 0.55),
        "friction": (0.01, 0.05),
    }
    for name, (down, up) in steps.items():
        start = getattr(demo.scene, name)
        assert demo.step_parameter(name, -1) and getattr(demo.scene, name) == pytest.approx(down)
        demo.set_parameter(name, start)
        assert demo.step_parameter(name, +1) and getattr(demo.scene, name) == pytest.approx(up)
    restitution = PARAMETER_BY_NAME["restitution"]
    assert restitution.next_value(1.0, +1) == 1.0 and restitution.next_value(0.0, -1) == 0.0
    for parameter in PARAMETERS:  # every ladder value is one the engine accepts
        for value in parameter.ladder:
            demo.scene.replace(**{parameter.name: value})


def test_rows_are_selected_and_changed_from_the_keyboard(demo):
    assert demo.selected_row == "dt"
    demo.select(-1)
    assert demo.selected_row == "solver"
    demo.select_row("restitution")
    demo.adjust(+1)
    assert demo.scene.restitution == pytest.approx(0.55)
    demo.select_row("use_penalty")
    demo.adjust(+1)
    assert demo.scene.use_penalty is False and demo.row_value("use_penalty") == "off"
    demo.begin_entry()  # Enter on a toggle flips it
    assert demo.scene.use_penalty is True and demo.entry is None


def test_typing_a_value(demo):
    demo.select_row("penalty_stiffness")
    demo.begin_entry()
    demo.type_text("25x0")  # letters other than e are dropped
    demo.backspace()
    demo.type_text("e1")
    assert demo.entry == "25e1"
    assert demo.commit_entry()
    assert demo.scene.penalty_stiffness == 250.0 and demo.entry is None
    demo.begin_entry()
    demo.type_text("7")
    demo.cancel_entry()
    assert demo.scene.penalty_stiffness == 250.0


def test_the_two_toggles(demo):
    assert demo.toggle("use_impulses") and demo.lanes[0].simulator.flags.use_impulses is False
    assert demo.toggle("use_penalty") and demo.lanes[0].simulator.flags.use_penalty is False
    run_frames(demo, 100)  # nothing acts but gravity: the boxes fall through the floor
    expected = 5.0 - 0.5 * 9.81 * (800 * 0.005) * (801 * 0.005)
    np.testing.assert_allclose(demo.lanes[0].state[:, layout.Y], expected)
    assert demo.toggle("use_impulses") and demo.toggle("use_penalty")


def test_the_robust_solver_refuses_to_run_without_impulses(demo):
    demo.toggle("use_impulses")
    assert not demo.switch_solver()
    assert "use_impulses must be True with solver='robust'" in demo.message
    assert demo.scene.solver == "seed"
    assert not demo.toggle_compare() and len(demo.lanes) == 1


def test_switching_solver_goes_on_from_the_same_state(demo):
    run_frames(demo, 30)
    state = demo.lanes[0].state.copy()
    assert demo.switch_solver()
    lane = demo.lanes[0]
    assert demo.scene.solver == lane.solver == lane.simulator.flags.solver == "robust"
    np.testing.assert_array_equal(lane.state, state)
    assert demo.readouts(0)[0] == "robust solver"
    run_frames(demo, 1)
    robust = scenes.seed_demo(solver="robust")
    Simulator.for_scene(robust, parallel=False).run(
        state,
        robust.body_params(),
        make_settings(robust, STEPS_PER_FRAME, until_rest=False),
        np.zeros((5, layout.STATS_SIZE)),
    )
    np.testing.assert_array_equal(lane.state, state)
    assert demo.switch_solver() and demo.scene.solver == "seed"


def test_compare_runs_both_solvers_side_by_side_from_the_start(demo):
    run_frames(demo, 10)
    demo.set_parameter("friction", 0.3)
    assert demo.toggle_compare()
    seed, robust = demo.lanes
    assert (seed.solver, robust.solver) == ("seed", "robust")
    assert seed.scene.friction == robust.scene.friction == 0.3
    np.testing.assert_array_equal(seed.state, robust.state)
    assert seed.steps == robust.steps == 0
    run_frames(demo, 150)
    # the seed scheme sinks into the floor under its weight (k = 100), the robust solver does not
    lowest = {
        lane.solver: box_vertices(lane.state[:, :2], lane.state[:, 2], lane.params[:, :2])[..., 1].min()
        for lane in demo.lanes
    }
    assert lowest["seed"] < -0.02 and lowest["robust"] > -0.005
    assert demo.set_parameter("restitution", 0.1)
    assert seed.params[0, layout.RESTITUTION] == robust.params[0, layout.RESTITUTION] == 0.1
    assert not demo.switch_solver()
    assert demo.row_value("solver") == "seed | robust"
    assert [demo.lane_at(c) for c in (0, 449, 450, 899, 900)] == [0, 0, 1, 1, None]
    state = seed.state.copy()
    assert demo.toggle_compare()
    assert demo.lanes == [seed] and not demo.compare
    np.testing.assert_array_equal(demo.lanes[0].state, state)


def test_dragging_pulls_the_box_to_the_cursor(demo):
    run_frames(demo, 100)  # the boxes lie on the floor
    lane = demo.lanes[0]
    camera = demo.lane_camera(0)
    centre = lane.state[2, :2].copy()
    assert demo.grab(camera.world_to_pixel(centre))
    assert demo.grab_lane == 0 and lane.grab.body == 2
    target = centre + [1.0, 2.0]
    demo.drag_to(camera.world_to_pixel(target))
    run_frames(demo, 15)
    np.testing.assert_allclose(lane.grab_point(), target, atol=0.15)
    demo.release()
    assert lane.grab is None and demo.grab_lane is None
    run_frames(demo, 1)
    assert lane.state[2, layout.Y] < target[1]  # let go, it falls
    assert not demo.grab(camera.world_to_pixel(np.array([centre[0], 4.0])))  # nothing there


def test_zoom_keeps_the_point_under_the_cursor_and_pan_moves_the_view(demo):
    scale = demo.view.pixels_per_metre
    pixel = (700.0, 200.0)
    point = demo.to_world(pixel)
    demo.zoom(2.0, pixel)
    assert demo.view.pixels_per_metre == pytest.approx(2 * scale)
    assert demo.lane_camera(0).pixels_per_metre == pytest.approx(2 * scale)
    np.testing.assert_allclose(demo.to_world(pixel), point, atol=1e-9)
    demo.zoom(0.5)
    assert demo.view.pixels_per_metre == pytest.approx(scale)
    point = demo.to_world(pixel)
    demo.pan(30.0, -20.0)
    np.testing.assert_allclose(demo.to_world((pixel[0] + 30.0, pixel[1] - 20.0)), point, atol=1e-9)
    demo.fit()
    assert demo.view.pixels_per_metre == pytest.approx(scale)


class FakeClock:
    """Each run is timed by two calls (start, stop); the stop call moves on by the next duration [s]."""

    def __init__(self, durations):
        self.durations = iter(durations)
        self.now = 0.0
        self.calls = 0

    def __call__(self) -> float:
        self.calls += 1
        if self.calls % 2 == 0:
            self.now += next(self.durations)
        return self.now


def test_ms_per_step_is_the_mean_over_the_last_fifty_steps():
    # 1 ms a step for 6 frames, then 2 ms
    controller = ViewerController(scenes.seed_demo(), clock=FakeClock([0.008] * 6 + [0.016] * 10))
    run_frames(controller, 6)
    assert controller.lanes[0].timer.mean_ms == pytest.approx(1.0)
    run_frames(controller, 1)  # 50 steps: 42 at 1 ms, 8 at 2 ms
    assert controller.lanes[0].timer.mean_ms == pytest.approx((42 * 1.0 + 8 * 2.0) / 50)
    assert "1.16 ms / step" in controller.readouts(0)
    run_frames(controller, 6)  # the 1 ms steps have left the window
    assert controller.lanes[0].timer.mean_ms == pytest.approx(2.0)
    timer = StepTimer()
    timer.record(1.0, 1000)
    assert len(timer.step_seconds) == TIMING_WINDOW_STEPS and timer.mean_ms == pytest.approx(1.0)


def test_a_diverging_run_stops_and_says_so():
    # a box deep in the floor with an absurd penalty stiffness: the force overflows to inf
    scene = Scene(boxes=(Box(position=(0.0, -10.0)),), solver="seed", penalty_stiffness=1e308)
    controller = ViewerController(scene)
    controller.advance_frame()
    lane = controller.lanes[0]
    assert lane.diverged is not None and controller.paused
    assert lane.diverged.step == 1 and lane.steps == 1
    assert "went non-finite at step 1" in controller.message
    assert any(line.startswith("DIVERGED at step 1") for line in controller.readouts(0))
    controller.advance_frame(force=True)
    assert lane.steps == 1  # a diverged lane does not step again
    controller.restart()
    assert lane.diverged is None and np.isfinite(lane.state).all() and not controller.paused


def test_the_seed_scheme_throws_a_stiff_box_into_the_air_and_the_robust_solver_does_not():
    controller = ViewerController(scenes.stiff(solver="seed"))
    controller.toggle_compare()
    heights, told = [], []
    for _ in range(50):
        controller.advance_frame()
        heights.append([lane.state[0, layout.Y] for lane in controller.lanes])
        told.append([any("1 out of view" in line for line in controller.readouts(k)) for k in (0, 1)])
    seed_height, robust_height = np.array(heights).T
    assert seed_height.max() > 2.0  # the explicit penalty force turns 1 cm of penetration into a 2 m jump
    np.testing.assert_allclose(robust_height, 0.5, atol=1e-3)
    y_max = controller.lane_camera(0).view_bounds[3]
    np.testing.assert_array_equal(np.array(told), np.column_stack([seed_height > y_max, robust_height > y_max]))


@pytest.mark.parametrize("name", sorted(scenes.SCENES))
def test_the_first_view_shows_every_box_of_every_named_scene(name):
    controller = ViewerController(scenes.SCENES[name]())
    x_min, x_max, y_min, y_max = controller.lane_camera(0).view_bounds
    points = view_points(controller.scene)
    assert (points[:, 0] > x_min).all() and (points[:, 0] < x_max).all()
    assert (points[:, 1] > y_min).all() and (points[:, 1] < y_max).all()
    assert y_min < 0.0 < y_max  # the floor is in view
    assert math.isfinite(controller.view.pixels_per_metre)


@pytest.mark.parametrize("solver", ["seed", "robust"])
def test_boxes_collide_toggle_makes_a_dragged_box_push_another(solver):
    """Dragging box 1 of the demo into box 2 (after they have landed): with "boxes collide" on, box 2 is
    pushed along and the two never pass through each other; off, box 1 passes through box 2."""
    moved = {}
    for collide in (False, True):
        demo = ViewerController(scenes.seed_demo(solver=solver, penalty_stiffness=1e3))
        run_frames(demo, 75)  # 3 s: every box lies on the floor
        if collide:
            assert demo.toggle("boxes_collide") and demo.lanes[0].simulator.flags.boxes_collide
            assert demo.row_value("boxes_collide") == "on"
        lane = demo.lanes[0]
        start = lane.state[:, :2].copy()
        assert lane.grab_at(start[1])
        lane.grab.target = start[1] + np.array([6.0, 0.5])  # far beyond box 2 (3 m to the right)
        left_of_it = []
        for _ in range(60):
            demo.advance_frame()
            left_of_it.append(lane.state[1, 0] < lane.state[2, 0])
        moved[collide] = lane.state[2, 0] - start[2, 0]
        if collide:
            assert all(left_of_it)
        else:
            assert not left_of_it[-1]  # it went through
    assert abs(moved[False]) < 0.2 and moved[True] > 1.0  # alone, box 2 creeps (the seed scheme: 8 cm)


def test_boxes_collide_from_the_command_line():
    from box_toss_env.viewer.__main__ import make_parser

    args = make_parser().parse_args(["--boxes-collide"])
    assert args.boxes_collide
