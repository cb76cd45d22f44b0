"""``python -m box_toss_env.viewer --frames N --out PATH``: PNG frames without a window that show the scene
where the state says (run in a subprocess with SDL_VIDEODRIVER=dummy, as CI does)."""

import os
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
from PIL import Image

import box_toss_env
from box_toss_env.envs.render import ThrowRenderer
from box_toss_env.physics import layout, scenes
from box_toss_env.rendering import Palette
from box_toss_env.viewer import PlayController, ViewerController
from box_toss_env.viewer.window import PANEL_WIDTH_PX

REPO_ROOT = Path(box_toss_env.__file__).resolve().parents[1]
BOX_FILL = Palette().box_fill
BACKGROUND = Palette().background


def run_viewer(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    environment = {
        **os.environ,
        "SDL_VIDEODRIVER": "dummy",
        "SDL_AUDIODRIVER": "dummy",
        "PYTHONPATH": os.pathsep.join([str(REPO_ROOT), os.environ.get("PYTHONPATH", "")]),
    }
    return subprocess.run(
        [sys.executable, "-m", "box_toss_env.viewer", *args],
        env=environment,
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        check=check,
        timeout=300,
    )


def read_png(path: Path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB"))


def pixel(frame: np.ndarray, camera, point, left: int = 0) -> tuple[int, int, int]:
    row, column = camera.pixel_index(point)
    return tuple(int(c) for c in frame[row, column + left])


def test_frames_show_the_boxes_where_the_state_says(tmp_path):
    run_viewer(
        "--frames", "3", "--skip", "100", "--out", str(tmp_path / "frames"), "--states", str(tmp_path / "states.npy")
    )
    paths = sorted((tmp_path / "frames").glob("*.png"))
    assert [p.name for p in paths] == ["frame_0000.png", "frame_0001.png", "frame_0002.png"]
    states = np.load(tmp_path / "states.npy")
    assert states.shape == (3, 1, 5, layout.STATE_SIZE)
    controller = ViewerController(scenes.seed_demo())  # the same scene, view and stepping, in this process
    for _ in range(100):
        controller.advance_frame()
    camera = controller.lane_camera(0)
    for path, state in zip(paths, states, strict=True):
        np.testing.assert_array_equal(state[0], controller.lanes[0].state)
        frame = read_png(path)
        assert frame.shape == (560, 900 + PANEL_WIDTH_PX, 3)
        for x, y in state[0, :, :2]:
            assert pixel(frame, camera, (x, y)) == BOX_FILL
            assert pixel(frame, camera, (x, y + 1.5)) == BACKGROUND  # nothing drawn above the resting boxes
        controller.advance_frame()


def test_compare_frames_show_each_solver_in_its_half(tmp_path):
    run_viewer(
        "--compare",
        "--frames",
        "1",
        "--skip",
        "40",
        "--out",
        str(tmp_path / "compare.png"),
        "--states",
        str(tmp_path / "states.npy"),
    )
    frame = read_png(tmp_path / "compare.png")
    seed_state, robust_state = np.load(tmp_path / "states.npy")[0]
    controller = ViewerController(scenes.seed_demo())
    controller.toggle_compare()
    camera = controller.lane_camera(0)
    assert not np.array_equal(seed_state, robust_state)
    for lane, state in enumerate((seed_state, robust_state)):
        for x, y in state[:, :2]:
            assert pixel(frame, camera, (x, y), left=lane * controller.lane_width_px) == BOX_FILL


def test_a_headless_throw_draws_the_aim_the_throw_and_where_it_ended(tmp_path):
    out = tmp_path / "play"
    result = run_viewer("--play", "--seed", "5", "--throw", "2.5,2.5,0", "--frames", "4", "--out", str(out))
    paths = sorted(out.glob("*.png"))
    assert len(paths) == 4, result.stdout
    env = gym.make("BoxToss-v0", render_mode="rgb_array_list", render_width=720, render_height=480)
    play = PlayController(env, seed=5)
    throw = play.throw((2.5, 2.5), 0.0)
    camera = ThrowRenderer(play.config, 720, 480, 30).renderer.camera
    first, last = read_png(paths[0]), read_png(paths[-1])
    assert first.shape == last.shape == (480, 720 + PANEL_WIDTH_PX, 3)
    x, y, angle = play.release
    behind_the_arrow = (x - 0.12 * np.cos(angle), y - 0.12 * np.sin(angle))  # the aim arrow starts at the centre
    assert pixel(first, camera, behind_the_arrow) == BOX_FILL  # in the hand
    assert throw.info["at_rest"]
    final = (throw.info["final_x"], throw.info["final_y"])
    assert pixel(last, camera, final) == BOX_FILL
    np.testing.assert_array_equal(last[:, :720], throw.frames[-1])  # the env's own last frame
    env.close()


def test_bad_arguments_and_a_missing_render_extra_are_reported(tmp_path):
    result = run_viewer("--frames", "1", check=False)
    assert result.returncode == 2 and "--frames and --out go together" in result.stderr
    result = run_viewer("--restitution", "2", "--frames", "1", "--out", str(tmp_path), check=False)
    assert result.returncode == 2 and "restitution must be in [0, 1], got 2.0" in result.stderr
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO_ROOT), os.environ.get("PYTHONPATH", "")])}
    code = (
        "import sys; sys.modules['pygame'] = None; from box_toss_env.viewer.__main__ import main; "
        f"sys.exit(main(['--frames', '1', '--out', {str(tmp_path / 'x.png')!r}]))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], env=environment, cwd=REPO_ROOT, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 1 and 'pip install "box_toss_env[render]"' in result.stderr


def test_list_scenes():
    result = run_viewer("--list-scenes")
    assert "seed_demo" in result.stdout and "toss" in result.stdout
