"""``python -m box_toss_env.viewer``: the seed demo (or any named scene) to play with, BoxToss by hand
(``--play``), or frames to PNG without a window (``--frames N --out PATH``)."""

from __future__ import annotations

import argparse
import sys

import numpy as np
from gymnasium.error import DependencyNotInstalled

from box_toss_env.files import atomic_path
from box_toss_env.physics.scene import SOLVERS
from box_toss_env.physics.scenes import SCENES
from box_toss_env.viewer.controller import STEPS_PER_FRAME, ViewerController
from box_toss_env.viewer.kernel_loader import KernelLoader

PARAMETER_FLAGS = (
    ("dt", "dt", "time step size [s]"),
    ("gravity", "gravity", "gravity along y [m/s^2]"),
    ("stiffness", "penalty_stiffness", "penalty stiffness [N/m]"),
    ("restitution", "restitution", "restitution coefficient"),
    ("friction", "friction", "friction coefficient"),
)


# (flag, low, high) of the integer options: sizes in pixels, counts and seeds
INTEGER_FLAGS = (
    ("width", 100, 10_000),
    ("height", 100, 10_000),
    ("steps-per-frame", 1, 10_000),
    ("skip", 0, None),
    ("seed", 0, None),
)


def read_throw(text: str, config) -> list[float]:
    """``VX,VY,SPIN`` as three finite numbers within the env's limits (a ValueError naming them otherwise)."""
    try:
        throw = [float(v) for v in text.split(",")]
    except ValueError:
        throw = []
    if len(throw) != 3 or not all(np.isfinite(throw)):
        raise ValueError(f"--throw must be VX,VY,SPIN (three finite numbers), got {text!r}")
    speed = float(np.hypot(throw[0], throw[1]))
    if speed > config.max_speed or abs(throw[2]) > config.max_spin:
        raise ValueError(
            f"--throw {text}: the env throws at speeds up to {config.max_speed:g} m/s (this one "
            f"{speed:.3g}) and spins up to {config.max_spin:g} rad/s in magnitude "
            f"(this one {throw[2]:.3g})"
        )
    return throw


class OneLineParser(argparse.ArgumentParser):
    """A parser whose errors are one line (argparse would print the whole usage first)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def make_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="box-toss view",
        description="The seed demo's rigid-body viewer (any named scene), or BoxToss played by hand (--play). "
        "Keys are listed in the window's panel.",
        epilog="Headless: --frames N --out PATH draws N frames to PNG without opening a window "
        "(PATH ending in .png names the file, otherwise it is a folder of frame_0000.png ...).",
    )
    parser.add_argument("--scene", default="seed_demo", choices=sorted(SCENES), help="named scene (default: seed_demo)")
    parser.add_argument("--list-scenes", action="store_true", help="list the named scenes and exit")
    parser.add_argument("--solver", choices=SOLVERS, help="solver (default: the scene's; the env's with --play)")
    for flag, _, help_text in PARAMETER_FLAGS:
        parser.add_argument(f"--{flag}", type=float, help=f"{help_text} (default: the scene's)")
    parser.add_argument("--no-impulses", action="store_true", help="switch impulses off (seed solver only)")
    parser.add_argument("--no-penalty", action="store_true", help="switch penalty forces off")
    parser.add_argument(
        "--boxes-collide",
        action="store_true",
        help="the boxes collide with one another too (the demo's meet only the floor); key B",
    )
    parser.add_argument("--compare", action="store_true", help="start with seed | robust side by side")
    parser.add_argument("--paused", action="store_true", help="start paused")
    parser.add_argument(
        "--steps-per-frame",
        type=int,
        default=STEPS_PER_FRAME,
        help=f"simulation steps per drawn frame (default {STEPS_PER_FRAME}, as in the demo)",
    )
    parser.add_argument("--width", type=int, help="scene area width [px] (default 900; play: 720)")
    parser.add_argument("--height", type=int, help="scene area height [px] (default 560; play: 480)")
    headless = parser.add_argument_group("headless frames (no window)")
    headless.add_argument("--frames", type=int, help="draw this many frames to PNG and exit")
    headless.add_argument("--out", help="PNG file or folder for --frames")
    headless.add_argument("--skip", type=int, default=0, help="frames to step before the first one drawn")
    headless.add_argument("--states", help="also save the drawn states to this .npy file, (frames, lanes, bodies, 6)")
    play = parser.add_argument_group("play mode")
    play.add_argument("--play", action="store_true", help="throw BoxToss's box by hand")
    play.add_argument("--env-id", default="BoxToss-v0", help="the env to play (default BoxToss-v0)")
    play.add_argument("--seed", type=int, default=0, help="seed of the targets (default 0)")
    play.add_argument("--throw", help="headless play: the throw as VX,VY,SPIN [m/s, m/s, rad/s]")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    if args.list_scenes:
        for name in sorted(SCENES):
            print(f"{name:14s} {SCENES[name].__doc__.splitlines()[0]}")
        return 0
    if (args.frames is None) != (args.out is None):
        parser.error("--frames and --out go together")
    if args.frames is not None and args.frames < 1:
        parser.error(f"--frames must be at least 1, got {args.frames}")
    if args.throw is not None and not (args.play and args.frames):
        parser.error("--throw is for headless play: --play --frames N --out PATH --throw VX,VY,SPIN")
    for flag, low, high in INTEGER_FLAGS:
        value = getattr(args, flag.replace("-", "_"))
        if value is not None and not low <= value <= (high if high is not None else value):
            parser.error(f"--{flag} must be an integer in [{low}, {high if high is not None else 'inf'}], got {value}")
    try:
        return run_play(parser, args) if args.play else run_viewer(parser, args)
    except DependencyNotInstalled as error:
        print(f"error: {error}", file=sys.stderr)
        return 1


def run_viewer(parser: argparse.ArgumentParser, args) -> int:
    from box_toss_env.viewer.window import ViewerWindow

    changes = {field: getattr(args, flag) for flag, field, _ in PARAMETER_FLAGS if getattr(args, flag) is not None}
    if args.solver is not None:
        changes["solver"] = args.solver
    if args.no_impulses:
        changes["use_impulses"] = False
    if args.no_penalty:
        changes["use_penalty"] = False
    if args.boxes_collide:
        changes["boxes_collide"] = True
    # in a window, kernels load on a background thread after the first frame (headless: at the first step)
    loader = KernelLoader() if args.frames is None else None
    try:
        scene = SCENES[args.scene]().replace(**changes)
        controller = ViewerController(
            scene,
            width_px=args.width or 900,
            height_px=args.height or 560,
            steps_per_frame=args.steps_per_frame,
            loader=loader,
        )
    except ValueError as error:
        parser.error(str(error))
    if args.compare and not controller.toggle_compare():
        parser.error(controller.message)
    controller.paused = args.paused
    window = ViewerWindow(controller, args.scene, headless=args.frames is not None)
    if args.frames is None:
        window.run()
        return 0
    paths, states = window.write_frames(args.frames, args.out, skip=args.skip)
    if args.states:
        destination = args.states if args.states.endswith(".npy") else args.states + ".npy"  # as np.save names it
        with atomic_path(destination) as temp:
            np.save(temp, states)
    print(f"wrote {len(paths)} frame(s): {paths[0]}" + (f" ... {paths[-1]}" if len(paths) > 1 else ""))
    return 0


def run_play(parser: argparse.ArgumentParser, args) -> int:
    import gymnasium as gym

    import box_toss_env  # noqa: F401  (registers the envs)
    from box_toss_env.viewer.play import PlayController
    from box_toss_env.viewer.play_window import PlayWindow

    kwargs = {"render_mode": "rgb_array_list", "render_width": args.width or 720, "render_height": args.height or 480}
    if args.solver is not None:
        kwargs["solver"] = args.solver
    try:
        env = gym.make(args.env_id, **kwargs)
    except (ValueError, gym.error.Error) as error:
        parser.error(str(error))
    try:
        throw = None if args.throw is None else read_throw(args.throw, env.unwrapped.config)
    except ValueError as error:
        env.close()
        parser.error(str(error))
    try:
        headless = args.frames is not None
        window = PlayWindow(
            PlayController(env, seed=args.seed), headless=headless, loader=None if headless else KernelLoader()
        )
        if args.frames is None:
            window.run()
            return 0
        paths = window.write_frames(args.frames, args.out, throw=throw)
        print(f"wrote {len(paths)} frame(s): {paths[0]}" + (f" ... {paths[-1]}" if len(paths) > 1 else ""))
        return 0
    finally:
        env.close()


if __name__ == "__main__":
    sys.exit(main())
