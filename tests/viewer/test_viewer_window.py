"""The pygame front ends: keys, clicks, drags and the wheel reach the controllers; the loops run headless."""

import os

import gymnasium as gym
import numpy as np
import pytest

import box_toss_env  # noqa: F401  (registers the envs)
from box_toss_env.physics import scenes
from box_toss_env.rendering import import_pygame
from box_toss_env.viewer import PlayController, ViewerController
from box_toss_env.viewer.controller import ZOOM_STEP
from box_toss_env.viewer.window import PlayWindow, ViewerWindow, scene_subtitle

os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
pygame = import_pygame()


def key(code: int, text: str = "") -> "pygame.event.Event":
    return pygame.event.Event(pygame.KEYDOWN, key=code, unicode=text, mod=0)


def mouse(kind: int, pos, button: int = 1, rel=(0, 0)) -> "pygame.event.Event":
    if kind == pygame.MOUSEMOTION:
        return pygame.event.Event(kind, pos=pos, rel=rel, buttons=(1, 0, 0))
    return pygame.event.Event(kind, pos=pos, button=button)


@pytest.fixture
def window():
    viewer = ViewerWindow(ViewerController(scenes.seed_demo()), "seed_demo", headless=True)
    viewer.draw()
    return viewer


def test_keys_drive_the_controller(window):
    controller = window.controller
    assert window.handle(key(pygame.K_SPACE, " ")) and controller.paused
    window.handle(key(pygame.K_PERIOD, "."))
    assert controller.lanes[0].steps == 8
    window.handle(key(pygame.K_r, "r"))
    assert controller.lanes[0].steps == 0 and not controller.paused
    window.handle(key(pygame.K_DOWN))
    window.handle(key(pygame.K_RIGHT))
    assert controller.scene.gravity == -9.0
    for code, text in ((pygame.K_3, "3"), (pygame.K_BACKSPACE, ""), (pygame.K_4, "4"), (pygame.K_RETURN, "\r")):
        window.handle(key(code, text))  # digits start typing into the selected row
    assert controller.scene.gravity == 4.0
    window.handle(key(pygame.K_p, "p"))
    window.handle(key(pygame.K_i, "i"))
    assert not controller.scene.use_penalty and not controller.scene.use_impulses
    window.handle(key(pygame.K_i, "i"))
    window.handle(key(pygame.K_p, "p"))
    window.handle(key(pygame.K_s, "s"))
    assert controller.scene.solver == "robust"
    window.handle(key(pygame.K_c, "c"))
    assert controller.compare and len(controller.lanes) == 2
    window.draw()
    scale = controller.view.pixels_per_metre
    window.handle(key(pygame.K_EQUALS, "="))
    assert controller.view.pixels_per_metre == pytest.approx(scale * ZOOM_STEP)
    window.handle(key(pygame.K_f, "f"))
    assert controller.view.pixels_per_metre == pytest.approx(scale)
    assert not window.handle(key(pygame.K_ESCAPE))
    assert not window.handle(pygame.event.Event(pygame.QUIT))


def test_clicks_on_the_panel_and_drags_in_the_scene(window):
    controller = window.controller
    window.handle(mouse(pygame.MOUSEBUTTONDOWN, window.button_rects["pause"].center))
    assert controller.paused
    window.handle(mouse(pygame.MOUSEBUTTONDOWN, window.row_rects["use_impulses"].center))
    assert controller.selected_row == "use_impulses" and not controller.scene.use_impulses
    window.handle(mouse(pygame.MOUSEBUTTONDOWN, window.button_rects["restart"].center))
    assert not controller.paused

    camera = controller.lane_camera(0)
    centre = controller.lanes[0].state[1, :2].copy()
    start = tuple(camera.world_to_pixel(centre))
    window.handle(mouse(pygame.MOUSEBUTTONDOWN, start))
    assert controller.grab_lane == 0 and controller.lanes[0].grab.body == 1
    end = tuple(camera.world_to_pixel(centre + [0.0, 1.0]))
    window.handle(mouse(pygame.MOUSEMOTION, end, rel=(0, end[1] - start[1])))
    np.testing.assert_allclose(controller.lanes[0].grab.target, centre + [0.0, 1.0])
    window.draw()  # with the drag line
    window.handle(mouse(pygame.MOUSEBUTTONUP, end))
    assert controller.grab_lane is None

    point = controller.to_world((200, 300))
    window.handle(mouse(pygame.MOUSEMOTION, (200, 300)))
    window.handle(pygame.event.Event(pygame.MOUSEWHEEL, x=0, y=2))
    np.testing.assert_allclose(controller.to_world((200, 300)), point, atol=1e-9)
    window.handle(mouse(pygame.MOUSEBUTTONDOWN, (200, 300), button=3))
    window.handle(mouse(pygame.MOUSEMOTION, (260, 300), rel=(60, 0)))
    window.handle(mouse(pygame.MOUSEBUTTONUP, (260, 300), button=3))
    np.testing.assert_allclose(controller.to_world((260, 300)), point, atol=1e-9)


def test_the_viewer_loop_runs_and_quits():
    viewer = ViewerWindow(ViewerController(scenes.toss()), "toss")
    viewer.run(max_frames=3)
    assert viewer.controller.lanes[0].steps == 24
    assert not pygame.display.get_init()
    viewer = ViewerWindow(ViewerController(scenes.toss()), "toss")
    pygame.event.post(pygame.event.Event(pygame.QUIT))
    viewer.run(max_frames=3)
    assert viewer.controller.lanes[0].steps == 0


def test_play_window_throws_on_release():
    env = gym.make("BoxToss-v0", render_mode="rgb_array_list")
    play_window = PlayWindow(PlayController(env, seed=2), headless=True)
    play = play_window.controller
    centre = play.release[:2]
    start = tuple(play_window.camera.world_to_pixel(centre))
    end = tuple(play_window.camera.world_to_pixel(centre + [0.4, 0.5]))
    play_window.handle(pygame.event.Event(pygame.MOUSEWHEEL, x=0, y=1))
    assert play.spin == pytest.approx(2.0)
    play_window.handle(mouse(pygame.MOUSEBUTTONDOWN, start))
    play_window.handle(mouse(pygame.MOUSEMOTION, end))
    play_window.draw()  # the aim
    play_window.handle(mouse(pygame.MOUSEBUTTONUP, end))
    result = play.result
    assert result is not None and len(result.frames) > 2
    np.testing.assert_allclose(result.throw[2], 2.0, rtol=1e-6)
    assert result.throw[1] == pytest.approx(np.arctan2(0.5, 0.4), abs=1e-6)
    assert play_window.playback_index() == 0
    play_window.draw(0)
    play_window.draw(None)  # the end, with the reward
    target = play.target_x
    play_window.handle(key(pygame.K_n, "n"))
    assert play.result is None and play.target_x != target
    assert not play_window.handle(key(pygame.K_ESCAPE))
    env.close()


def test_key_b_switches_boxes_collide(window):
    controller = window.controller
    window.handle(key(pygame.K_b, "b"))
    assert controller.scene.boxes_collide and controller.lanes[0].simulator.flags.boxes_collide
    window.handle(key(pygame.K_b, "b"))
    assert not controller.scene.boxes_collide


def test_the_panel_says_how_many_steps_a_frame_draws(monkeypatch):
    drawn = []
    monkeypatch.setattr(
        "box_toss_env.viewer.window.Panel.line",
        lambda self, text="", *args, **kwargs: drawn.append(text) or pygame.Rect(0, 0, 1, 1),
    )
    ViewerWindow(
        ViewerController(scenes.seed_demo(boxes_collide=True), steps_per_frame=3), "seed_demo", headless=True
    ).draw()
    assert "boxes against the floor and one another, 3 steps a frame" in drawn
    assert scene_subtitle(False, 1) == "boxes against the floor, 1 step a frame"
