"""The ceiling of ``BoxToss-Stack-v0``: a planner that searches each throw with the simulator.

For every throw of an episode, a cross-entropy search over a throw command simulates candidate throws onto
copies of the current scene (``BoxTossStackEnv.try_throws``: all candidates of a round in one call of the
engine's colliding kernel), then throws the best one for real. The search is per throw and greedy: it
scores a candidate by the env's reward of that throw, with the height it adds credited up to the thrown box's
width only, minus ``centring_weight`` times how far the thrown box's centre ended from the target x (a box lying
flat and centred is the best base for the next one, and a greedy search that credits a box stood on its end
would prefer it). Its first candidates are lobs flat onto the stack's centre
(``PRIOR_COMMANDS``). Since a copy's simulation is bit for bit the env's, the throw made is exactly the one scored.

The command c in [-1, 1]^3 is ``envs.stack_commands``' (flight time, touchdown offset from the target x, lean
from lying flat, aimed at the stack's top), the action space PPO is trained in too.

    python -m agents.stack_planner --episodes 50 --readme      # success, height, throws simulated, seconds per budget
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import cast

import gymnasium as gym
import numpy as np

from agents.doc_sections import REPO, replace_section
from box_toss_env.envs import stack_commands, stack_task
from box_toss_env.envs.stack import BoxTossStackEnv
from box_toss_env.files import write_atomic

TEST_FIRST_SEED = 10_000  # episodes are seeds 10000, 10001, ... (as the one-throw test targets)


@dataclass(frozen=True)
class StackPlannerSettings:
    """The search budget per throw: ``initial`` uniform commands, then up to ``iterations`` rounds of
    ``population`` commands drawn around the ``elite`` best so far (a Gaussian, its spread shrinking to
    theirs); it stops early once a throw lands the box flat and centred on the stack."""

    initial: int = 64
    population: int = 32
    elite: int = 6
    iterations: int = 3
    flight_time_range: tuple[float, float] = stack_commands.FLIGHT_TIME_RANGE  # [s]
    offset_range: float = stack_commands.OFFSET_RANGE  # [m]
    turn_range: float = stack_commands.TURN_RANGE  # [rad]
    centring_weight: float = 1.0  # [1/m]
    threads: int | None = 1


def command_actions(
    observation: np.ndarray, commands: np.ndarray, config: stack_task.StackConfig, settings: StackPlannerSettings
) -> np.ndarray:
    """The env actions (m, 3) of ``commands`` (m, 3) in [-1, 1] from ``observation`` (``envs.stack_commands``)."""
    return stack_commands.command_actions(
        observation, commands, config, settings.flight_time_range, settings.offset_range, settings.turn_range
    )


PRIOR_COMMANDS = np.array([[c0, 0.0, 0.0] for c0 in (-0.6, -0.2, 0.2, 0.6, 1.0)])
"""Lobs flat onto the stack's centre, of five flight times: the first candidates of every search."""


class StackPlanner:
    """Plans each throw of a ``BoxToss-Stack-v0`` episode by a cross-entropy search with the simulator."""

    def __init__(self, settings: StackPlannerSettings = StackPlannerSettings(), seed: int = 0):
        self.settings = settings
        self.rng = np.random.default_rng(seed)
        self.simulated = 0  # candidate throws simulated so far

    def plan(self, env: gym.Env, observation: np.ndarray) -> np.ndarray:
        """The best action (3,) found for the box in the hand of ``env`` (which it leaves as it was)."""
        unwrapped = cast(BoxTossStackEnv, env.unwrapped)
        config = unwrapped.config
        settings = self.settings
        k = unwrapped.thrown
        width = float(observation[stack_task.BODY_SIZE * k + stack_task.B_WIDTH])  # of the box in the hand
        commands = self.rng.uniform(-1.0, 1.0, (settings.initial, 3))
        prior = PRIOR_COMMANDS[: settings.initial]
        commands[: len(prior)] = prior
        best_score, best_action = -np.inf, None
        all_commands, all_scores = np.zeros((0, 3)), np.zeros(0)
        for round_ in range(settings.iterations + 1):
            actions = command_actions(observation, commands, config, settings)
            tried = unwrapped.try_throws(actions, threads=settings.threads)
            self.simulated += len(actions)
            centre = np.abs(tried.states[:, k, 0] - unwrapped.target_x)
            # a box lying flat is the best base for the next: height beyond its width is not credited
            height = tried.info["reward_height"]
            scores = (
                tried.reward
                - height
                + np.minimum(height, config.height_weight * width)
                - settings.centring_weight * centre
            )
            i = int(np.argmax(scores))
            if scores[i] > best_score:
                best_score, best_action = scores[i], actions[i]
            all_commands, all_scores = np.vstack((all_commands, commands)), np.concatenate((all_scores, scores))
            flat_on_top = height[i] >= 0.95 * config.height_weight * width
            if tried.info["success"][i] or (flat_on_top and centre[i] < 0.03 and not tried.info["fell"][i]):
                break
            if round_ == settings.iterations:
                break
            elite = all_commands[np.argsort(all_scores)[-settings.elite :]]
            mean, std = elite.mean(axis=0), np.maximum(elite.std(axis=0), 0.02)
            commands = np.clip(self.rng.normal(mean, std, (settings.population, 3)), -1.0, 1.0)
        assert best_action is not None  # the first round scores its candidates
        return best_action


def play_episodes(n_episodes: int, act, first_seed: int = TEST_FIRST_SEED, env_kwargs: dict | None = None) -> dict:
    """``act(env, observation) -> action`` on episodes seeded ``first_seed``, ``first_seed + 1``, ...: its success
    rate, mean final stack height [m], falls, throws made and seconds."""
    env = gym.make("BoxToss-Stack-v0", **(env_kwargs or {}))
    successes, heights, falls, throws = [], [], [], 0
    start = time.perf_counter()
    for episode in range(n_episodes):
        observation, _ = env.reset(seed=first_seed + episode)
        terminated = False
        while not terminated:
            observation, _, terminated, _, info = env.step(act(env, observation))
            throws += 1
        successes.append(info["success"])
        heights.append(info["stack_height"])
        falls.append(info["fell"])
    seconds = time.perf_counter() - start
    env.close()
    return {
        "episodes": n_episodes,
        "success_rate": float(np.mean(successes)),
        "mean_height": float(np.mean(heights)),
        "fall_rate": float(np.mean(falls)),
        "throws": throws,
        "seconds": seconds,
    }


def run_episodes(
    n_episodes: int,
    settings: StackPlannerSettings = StackPlannerSettings(),
    first_seed: int = TEST_FIRST_SEED,
    env_kwargs: dict | None = None,
) -> dict:
    """The planner on ``play_episodes``' episodes, with the candidate throws it simulated per throw made."""
    planner = StackPlanner(settings)
    result = play_episodes(n_episodes, planner.plan, first_seed, env_kwargs)
    return {**result, "simulated_per_throw": planner.simulated / max(result["throws"], 1), "budget": asdict(settings)}


def zoo_policy(run_dir: Path):
    """``act(env, observation)`` of a PPO model that RL Zoo trained on ``BoxToss-Stack-v0`` in throw commands
    (``run_dir`` holds ``BoxToss-Stack-v0.zip`` and, with normalisation, ``BoxToss-Stack-v0/vecnormalize.pkl``);
    it acts deterministically (the mean command)."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    model = PPO.load(run_dir / "BoxToss-Stack-v0.zip", device="cpu")
    statistics = run_dir / "BoxToss-Stack-v0" / "vecnormalize.pkl"
    normalize = None
    if statistics.exists():
        normalize = VecNormalize.load(str(statistics), DummyVecEnv([lambda: gym.make("BoxToss-Stack-v0")]))
        normalize.training = False

    def act(env: gym.Env, observation: np.ndarray) -> np.ndarray:
        seen = normalize.normalize_obs(observation[None]) if normalize is not None else observation[None]
        command, _ = model.predict(seen, deterministic=True)
        return stack_commands.command_actions(observation, command, cast(BoxTossStackEnv, env.unwrapped).config)[
            0
        ].astype(np.float32)

    return act


BUDGETS = {
    "small": StackPlannerSettings(initial=16, population=8, elite=4, iterations=1),
    "default": StackPlannerSettings(),
    "large": StackPlannerSettings(initial=128, population=64, elite=8, iterations=5),
}
"""Growing searches per throw: the ceiling is the success where a larger one stops raising it."""


RESULTS = REPO / "docs" / "agents" / "stack_ceiling.json"
"""Each budget's measured row, kept so that runs of different budgets (at once, or one after another) make one
table."""


def budget_table(rows: list[dict]) -> str:
    """The measured rows (``run_episodes``' results with their budget's ``name``) as docs/stack.md's section."""
    lines = [
        "| budget (initial, population, elite, rounds) | episodes (seeds) | success | mean final height | "
        "stack fell | throws simulated per throw | seconds |",
        "|---|---|---|---|---|---|---|",
    ]
    for result in rows:
        b = result["budget"]
        lines.append(
            f"| {result['name']} ({b['initial']}, {b['population']}, {b['elite']}, {b['iterations']}) | "
            f"{result['episodes']} ({result['first_seed']}...) | {100 * result['success_rate']:.1f}% | "
            f"{result['mean_height']:.3f} m | {100 * result['fall_rate']:.1f}% | "
            f"{result['simulated_per_throw']:.0f} | {result['seconds']:.0f} |"
        )
    return (
        "Measured on the default `BoxToss-Stack-v0` (a hand of 4), one engine thread, the 2 cores shared with "
        "other jobs (seconds are wall time), by `python -m agents.stack_planner --episodes N --budgets NAME "
        "--readme` (each run adds its rows to `docs/agents/stack_ceiling.json` and writes the table of all):"
        "\n\n" + "\n".join(lines)
    )


def saved_rows(path: Path = RESULTS) -> list[dict]:
    return json.loads(path.read_text()) if path.exists() else []


def save_row(row: dict, path: Path = RESULTS) -> list[dict]:
    """Add ``row`` to the saved rows (replacing one of the same budget name), ordered by budget size."""
    order = list(BUDGETS)
    rows = [r for r in saved_rows(path) if r["name"] != row["name"]] + [row]
    rows.sort(key=lambda r: order.index(r["name"]) if r["name"] in order else len(order))
    write_atomic(path, json.dumps(rows, indent=1) + "\n")
    return rows


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m agents.stack_planner", description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--first-seed", type=int, default=TEST_FIRST_SEED)
    parser.add_argument("--budgets", nargs="+", choices=sorted(BUDGETS), default=list(BUDGETS))
    parser.add_argument(
        "--readme",
        action="store_true",
        help="save the rows in docs/agents/stack_ceiling.json and write the table into docs/stack.md "
        "(with --model: the PPO section)",
    )
    parser.add_argument("--model", type=Path, help="evaluate this RL Zoo run folder's PPO instead of the planner")
    args = parser.parse_args(argv)
    if args.model is not None:
        result = play_episodes(args.episodes, zoo_policy(args.model), args.first_seed)
        line = (
            f"success {100 * result['success_rate']:.1f}%, mean final height {result['mean_height']:.3f} m, "
            f"stack fell {100 * result['fall_rate']:.1f}% on {result['episodes']} episodes (seeds "
            f"{args.first_seed}...)"
        )
        print(f"{args.model}: {line}")
        if args.readme:
            command = f"python -m agents.stack_planner --model {args.model} --episodes {args.episodes} --readme"
            replace_section("stack-ppo", f"PPO, acting deterministically: {line}; by `{command}`.")
        return
    for name in args.budgets:
        result = {
            "name": name,
            "first_seed": args.first_seed,
            **run_episodes(args.episodes, BUDGETS[name], args.first_seed),
        }
        print(
            f"{name}: success {100 * result['success_rate']:.1f}%, mean final height {result['mean_height']:.3f} m, "
            f"falls {100 * result['fall_rate']:.1f}%, {result['simulated_per_throw']:.0f} candidate throws "
            f"simulated per throw, {result['seconds']:.1f} s",
            flush=True,
        )
        if args.readme:
            replace_section("stack-ceiling", budget_table(save_row(result)))


if __name__ == "__main__":
    main()
