"""The first frame is on screen before any kernel is loaded or compiled, a notice says which kernel is
compiling while the scene waits for it, and the notice goes once the kernel is ready.

The kernel's load (``kernels.load_kernel``) is replaced by one that blocks until the test opens a gate,
and the kernels count as not compiled yet (``compiled_in_process``) and not on disk (``cached_on_disk``),
so the tests see the first use of a kernel whatever ran before them. Nothing is timed."""

import os
import threading

import gymnasium as gym
import numpy as np
import pytest

import box_toss_env  # noqa: F401  (registers the envs)
from box_toss_env.physics import Simulator, scenes
from box_toss_env.rendering import import_pygame
from box_toss_env.viewer import PlayController, ViewerController
from box_toss_env.viewer import kernel_loader as kernels
from box_toss_env.viewer import window as window_module
from box_toss_env.viewer.__main__ import main
from box_toss_env.viewer.kernel_loader import KernelLoader
from box_toss_env.viewer.window import NOTICE_BACKGROUND, PlayWindow, ViewerWindow

os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
pygame = import_pygame()

SAFETY_TIMEOUT_S = 120.0  # only so that a broken test cannot hang; never asserted on
MAX_FRAMES = 20_000


class Recorder:
    """Records, in order, frames shown (with the notices drawn on them), kernel loads and kernel runs."""

    def __init__(self, monkeypatch):
        self.events: list[tuple] = []
        self.gate = threading.Event()
        self._notices: list[str] = []
        real_load = kernels.load_kernel
        real_notice = window_module.Canvas.notice
        real_run = Simulator.run
        recorder = self

        def blocking_load(kernel, args):
            recorder.events.append(("load-start",))
            assert recorder.gate.wait(SAFETY_TIMEOUT_S), "the test never opened the gate"
            real_load(kernel, args)
            recorder.events.append(("load-end",))

        def drawn_notice(canvas, lines, left, width):
            rect = real_notice(canvas, lines, left, width)
            # drawn, not just asked for: the notice's background is on the surface
            assert tuple(canvas.surface.get_at((rect.left + 4, rect.top + 4)))[:3] == NOTICE_BACKGROUND
            recorder._notices.append(lines[0])
            return rect

        def counted_run(simulator, *args, **kwargs):
            recorder.events.append(("run",))
            return real_run(simulator, *args, **kwargs)

        monkeypatch.setattr(kernels, "load_kernel", blocking_load)
        monkeypatch.setattr(kernels, "compiled_in_process", lambda kernel, args: False)
        monkeypatch.setattr(kernels, "cached_on_disk", lambda kernel, args: False)
        monkeypatch.setattr(window_module.Canvas, "notice", drawn_notice)
        monkeypatch.setattr(Simulator, "run", counted_run)

    def frame_shown(self) -> tuple:
        """Call when a frame is shown: records it with the notices drawn since the last one."""
        event = ("frame", tuple(self._notices))
        self._notices = []
        self.events.append(event)
        return event

    def frames(self) -> list[tuple]:
        return [event for event in self.events if event[0] == "frame"]

    def index(self, kind: str) -> int:
        return next(i for i, event in enumerate(self.events) if event[0] == kind)


def test_the_window_shows_its_first_frame_with_the_notice_before_the_kernel_loads(monkeypatch):
    recorder = Recorder(monkeypatch)
    real_flip = pygame.display.flip

    def flip():
        real_flip()
        recorder.frame_shown()
        frames = recorder.frames()
        if len(frames) == 5:
            recorder.gate.set()  # five frames drawn while the kernel's load was blocked: let it load
        done = any(event[0] == "run" for event in recorder.events) and not frames[-1][1]
        if done or len(frames) >= MAX_FRAMES:
            pygame.event.post(pygame.event.Event(pygame.QUIT))

    monkeypatch.setattr(pygame.display, "flip", flip)
    assert main([]) == 0  # the seed demo in a window (SDL's dummy driver)

    events, frames = recorder.events, recorder.frames()
    notice = "compiling the seed kernel... (first use only)"
    # the first frame is shown before any kernel is loaded, compiled or run, with the notice on it
    assert events[0] == ("frame", (notice,))
    # frames kept coming, with the notice, while the load was blocked
    assert frames[:5] == [("frame", (notice,))] * 5
    assert recorder.index("frame") < recorder.index("load-start") < recorder.index("load-end")
    # the scene waited for the kernel: it first ran after the load, and from then on the notice is gone
    first_run = recorder.index("run")
    assert first_run > recorder.index("load-end")
    after = [event for event in events[first_run:] if event[0] == "frame"]
    assert after and all(notices == () for _, notices in after)
    assert len(frames) < MAX_FRAMES


def test_compare_mode_waits_for_both_kernels_and_names_each(monkeypatch):
    recorder = Recorder(monkeypatch)
    loader = KernelLoader()
    controller = ViewerController(scenes.seed_demo(), loader=loader)
    assert controller.toggle_compare()
    viewer = ViewerWindow(controller, "seed_demo", headless=True)
    viewer.draw()
    recorder.frame_shown()
    assert recorder.frames()[-1][1] == (
        "compiling the seed kernel... (first use only)",
        "compiling the robust kernel... (first use only)",
    )
    assert controller.loading and controller.notices() == [lane.job.notice for lane in controller.lanes]
    controller.advance_frame()
    controller.advance_frame(force=True)  # not even the step key steps without a kernel
    assert [lane.steps for lane in controller.lanes] == [0, 0]
    assert not any(event[0] in ("run", "load-start") for event in recorder.events)  # the loader has not started

    recorder.gate.set()
    assert controller.wait_for_kernels(SAFETY_TIMEOUT_S)
    assert not controller.loading and controller.notices() == [None, None]
    viewer.draw()
    assert recorder.frame_shown() == ("frame", ())
    controller.advance_frame()
    assert [lane.steps for lane in controller.lanes] == [8, 8]  # both lanes started together


def test_a_solver_switch_holds_the_scene_while_its_kernel_loads(monkeypatch):
    recorder = Recorder(monkeypatch)
    loader = KernelLoader()
    controller = ViewerController(scenes.seed_demo(), loader=loader)
    recorder.gate.set()
    assert controller.wait_for_kernels(SAFETY_TIMEOUT_S)
    controller.advance_frame()
    state = controller.lanes[0].state.copy()

    recorder.gate.clear()
    assert controller.switch_solver() and controller.scene.solver == "robust"
    assert controller.notices() == ["compiling the robust kernel... (first use only)"]
    controller.advance_frame()
    np.testing.assert_array_equal(controller.lanes[0].state, state)  # held where it was
    recorder.gate.set()
    assert controller.wait_for_kernels(SAFETY_TIMEOUT_S)
    controller.advance_frame()
    assert controller.notices() == [None] and controller.lanes[0].steps == 16
    assert controller.switch_solver() and controller.notices() == [None]  # the seed kernel is loaded already


def test_headless_frames_wait_for_the_kernels_and_show_no_notice(monkeypatch, tmp_path):
    recorder = Recorder(monkeypatch)
    recorder.gate.set()
    viewer = ViewerWindow(ViewerController(scenes.seed_demo(), loader=KernelLoader()), "seed_demo", headless=True)
    paths, states = viewer.write_frames(2, tmp_path)
    assert len(paths) == 2 and not np.array_equal(states[0], states[1])
    assert recorder.frame_shown() == ("frame", ())


def test_play_mode_loads_the_envs_kernel_and_throws_once_it_is_ready(monkeypatch):
    recorder = Recorder(monkeypatch)
    env = gym.make("BoxToss-v0", render_mode="rgb_array_list")
    try:
        loader = KernelLoader()
        play_window = PlayWindow(PlayController(env, seed=2), loader=loader)  # a window: SDL's dummy driver
        play = play_window.controller
        play_window.draw()
        notice = f"compiling the {env.unwrapped.solver} kernel... (first use only)"
        assert recorder.frame_shown() == ("frame", (notice,))

        centre = play.release[:2]
        start = tuple(play_window.camera.world_to_pixel(centre))
        end = tuple(play_window.camera.world_to_pixel(centre + [0.4, 0.5]))
        play_window.handle(pygame.event.Event(pygame.MOUSEBUTTONDOWN, pos=start, button=1))
        play_window.handle(pygame.event.Event(pygame.MOUSEMOTION, pos=end, rel=(0, 0), buttons=(1, 0, 0)))
        play_window.handle(pygame.event.Event(pygame.MOUSEBUTTONUP, pos=end, button=1))
        assert play.result is None and play_window.throw_pending  # released before the kernel was ready
        play_window.draw()
        assert recorder.frame_shown()[1]  # the notice is still there

        recorder.gate.set()
        assert loader.wait(SAFETY_TIMEOUT_S)
        play_window.run(max_frames=1)  # the loop throws the held throw
        recorder.frame_shown()
        assert not play_window.throw_pending and play.result is not None
        assert play.result.throw[1] == pytest.approx(np.arctan2(0.5, 0.4), abs=1e-6)
        assert recorder.frames()[-1] == ("frame", ())
        # the loader loaded the kernel the env throws with, so the throw compiled nothing more
        assert env.unwrapped._simulator.kernel is play_window.job.kernel
    finally:
        env.close()


def test_kernels_compiled_in_this_process_need_no_job():
    numba = pytest.importorskip("numba")

    @numba.njit(cache=False)
    def double(values):
        return 2.0 * values

    args = (np.ones(3),)
    assert not kernels.compiled_in_process(double, args)
    assert not kernels.cached_on_disk(double, args)  # no disk cache for this function
    loader = KernelLoader()
    job = loader.prepare(double, args, "double")
    assert job is not None and loader.prepare(double, args, "double") is job and not job.ready
    assert job.notice == "compiling the double kernel... (first use only)"
    assert loader.wait(SAFETY_TIMEOUT_S) and job.ready and job.error is None
    assert kernels.compiled_in_process(double, args)
    assert KernelLoader().prepare(double, args, "double") is None
    assert not kernels.compiled_in_process(len, args) and not kernels.cached_on_disk(len, args)
