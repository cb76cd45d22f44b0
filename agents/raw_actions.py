"""How wide a correct throw is, in the env's own actions and in ballistic commands: why SAC and TD3 trail PPO in
the raw tier.

For each of the first N test targets (seeds 10000...) of a one-throw variant, the oracle's cross-entropy search finds
a throw that succeeds, once in the env's actions (speed, direction, spin in [-1, 1]^3) and once in ballistic
commands (``envs.ballistic``: flight time, landing offset, lean, in [-1, 1]^3). Then ``draws`` throws per target
are made at that solution plus Gaussian noise of standard deviation sigma in each space (clipped to [-1, 1]): the
success of a Gaussian policy centred on a correct throw, as an off-policy learner's exploration makes them (TD3's
action noise, SAC's stochastic policy). The width of the region that succeeds, in each space, is what those numbers
measure; the commands' region is the wider one where they succeed at a larger sigma.

    python -m agents.raw_actions --targets 64 --readme      # the table in docs/methodology/raw-actions.md

With ``--by-face`` (a variant that names one face a target, BoxToss-ThisSideUp-v0), per target face: where the
throws that stand the box on it lie in the env's actions (``by_face``; section raw-faces). With ``--reach RUN`` (a
run folder trained on it): from the trained policy's throw for each long side, how often Gaussian exploration of
the env's actions stands the box on each short end (``reach``; section raw-face-reach).
"""

from __future__ import annotations

import argparse
import pickle
import time
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np

import box_toss_env  # noqa: F401  (registers the BoxToss envs)
from agents import oracle
from agents.doc_sections import replace_section
from agents.evaluation import draw_targets, load_policy, target_seeds
from agents.policies import Policy, TrainedPolicy, load_model
from box_toss_env.envs import task, task_columns, task_config
from box_toss_env.envs.ballistic import ballistic_actions
from box_toss_env.envs.task_columns import EP_TARGET_FACES, OBS_TARGET_FACES
from box_toss_env.physics import layout

SIGMAS = (0.01, 0.03, 0.1, 0.2, 0.3)
REACH_SIGMAS = (0.01, 0.03, 0.08)  # 0.08: the raw recipes' starting spread (log_std_init -2.5)
LINE_STEPS = tuple(round(0.1 * k, 1) for k in range(11))
ENVS = ("BoxToss-v0", "BoxToss-ThisSideUp-v0")


class CommandSimulator:
    """``oracle.ThrowSimulator`` acting in ballistic commands: each command mapped to the env's action from the
    episode's first observation, as ``BallisticThrows`` does."""

    def __init__(self, simulator: oracle.ThrowSimulator):
        self.simulator, self.config = simulator, simulator.config

    def actions(self, episodes: task_config.Episodes, commands: np.ndarray) -> np.ndarray:
        core = self.simulator.core
        observations = core.observation(core.for_episodes(episodes))
        return ballistic_actions(observations, commands, self.config)[0]

    def rewards(self, episodes: task_config.Episodes, commands: np.ndarray):
        return self.simulator.rewards(episodes, self.actions(episodes, commands))


def noisy_success(
    simulator, episodes: task_config.Episodes, solutions: np.ndarray, sigma: float, draws: int, rng: np.random.Generator
) -> float:
    """The success rate of ``draws`` throws per episode at its solution plus N(0, sigma^2) noise per dimension."""
    n = len(episodes.data)
    repeated = task_config.Episodes(np.repeat(episodes.data, draws, axis=0))
    noisy = np.clip(np.repeat(solutions, draws, axis=0) + sigma * rng.standard_normal((n * draws, 3)), -1.0, 1.0)
    return float(simulator.rewards(repeated, noisy)[1].mean())


def measure(env_id: str, n_targets: int, draws: int, sigmas=SIGMAS, seed: int = 0) -> dict:
    """Per space ("env actions", "ballistic commands"): the oracle's success on the targets, and the success of
    noisy throws around its solutions (the targets it solved) per sigma."""
    env = gym.make(env_id)
    _, infos = draw_targets(env, target_seeds(n_targets))
    episodes = oracle.episodes_from_infos(infos)
    base = oracle.ThrowSimulator(env, threads=1)
    result: dict[str, Any] = {"env_id": env_id, "targets": n_targets, "draws": draws, "spaces": {}}
    for name, simulator in (("env actions", base), ("ballistic commands", CommandSimulator(base))):
        start = time.perf_counter()
        planner = oracle.OraclePlanner(oracle.OracleSettings(threads=1, seed=seed))
        solutions = planner.plan(cast(oracle.ThrowSimulator, simulator), episodes)
        solved = simulator.rewards(episodes, solutions)[1]
        kept = task_config.Episodes(episodes.data[solved])
        rng = np.random.default_rng(seed)
        result["spaces"][name] = {
            "solved": float(solved.mean()),
            "noisy": {
                str(sigma): noisy_success(simulator, kept, solutions[solved], sigma, draws, rng) for sigma in sigmas
            },
            "seconds": time.perf_counter() - start,
        }
    env.close()
    return result


def by_face(env_id: str, n_targets: int, draws: int, sigma: float = 0.01, seed: int = 0) -> list[dict]:
    """Per target face of a face variant: where the throws that stand the box on it lie in the env's actions. The
    oracle plans in ballistic commands (it solves every target there); each solution is mapped to the env's action
    (speed, direction, spin in [-1, 1]); per face: how many targets, how many solved, each action dimension's range
    over the solutions, and the success of ``draws`` throws per target at the solution plus N(0, sigma^2) noise in
    the env's actions."""
    env = gym.make(env_id)
    _, infos = draw_targets(env, target_seeds(n_targets))
    episodes = oracle.episodes_from_infos(infos)
    base = oracle.ThrowSimulator(env, threads=1)
    commands = CommandSimulator(base)
    solutions = oracle.OraclePlanner(oracle.OracleSettings(threads=1, seed=seed)).plan(
        cast(oracle.ThrowSimulator, commands), episodes
    )
    actions = commands.actions(episodes, solutions)
    solved = base.rewards(episodes, actions)[1]
    faces = np.array([int(np.argmax(info["target_faces"])) for info in infos])
    rng = np.random.default_rng(seed)
    rows = []
    for face in range(4):
        chosen = (faces == face) & solved
        row: dict[str, Any] = {"face": face, "targets": int((faces == face).sum()), "solved": int(chosen.sum())}
        if chosen.any():
            row["low"], row["high"] = actions[chosen].min(axis=0).tolist(), actions[chosen].max(axis=0).tolist()
            kept = task_config.Episodes(episodes.data[chosen])
            row["noisy"] = noisy_success(base, kept, actions[chosen], sigma, draws, rng)
        rows.append(row)
    env.close()
    return rows


def with_face(
    observations: np.ndarray, episodes: task_config.Episodes, face: int
) -> tuple[np.ndarray, task_config.Episodes]:
    """The same targets (first observations and episodes) with ``face`` as their one target face."""
    observations, episodes = observations.copy(), task_config.Episodes(episodes.data.copy())
    observations[:, OBS_TARGET_FACES] = 0.0
    observations[:, OBS_TARGET_FACES.start + face] = 1.0
    episodes.data[:, EP_TARGET_FACES] = 0.0
    episodes.data[:, EP_TARGET_FACES.start + face] = 1.0
    return observations, episodes


def reach(
    policy: Policy, env_id: str, n_targets: int, draws: int, sigmas=REACH_SIGMAS, seed: int = 0
) -> dict[str, list]:
    """How far a trained policy's throws are from standing the box on each short end, on the first ``n_targets``
    test targets of a face variant, each made a target of every face in turn (the same throw positions and
    release poses for every face).

    ``zero``: the share of targets whose throw at action 0 (an untrained SB3 policy's mean: its last layer starts
    near 0) lands on each face. ``own``: per target face f, the success of the policy's own action for face f and
    its mean spin action.
    ``reach``: per start face s (a long side: 0, 2) and short end e (1, 3), the success, for face-e targets, of
    ``draws`` throws per target at the policy's face-s action plus N(0, sigma^2) noise per action dimension
    (clipped to [-1, 1]): how often PPO's Gaussian, centred on a learned long-side throw, stands the box on that
    end; ``targets`` is the share of targets with at least one such stand. ``line``: along the segment from the
    policy's face-0 throw to its face-2 throw (alpha 0 to 1), per short end the mean reward and the success of a
    target of that end, and the median distance from the target."""
    env = gym.make(env_id)
    observations, infos = draw_targets(env, target_seeds(n_targets))
    episodes = oracle.episodes_from_infos(infos)
    simulator = oracle.ThrowSimulator(env, threads=1)
    actions, relabelled = {}, {}
    own = []
    for face in range(4):
        obs, relabelled[face] = with_face(observations, episodes, face)
        actions[face] = np.asarray(policy.act(obs, infos, env), dtype=np.float64).reshape(n_targets, -1)
        success = simulator.rewards(relabelled[face], actions[face])[1]
        own.append({"face": face, "success": float(success.mean()), "spin": float(actions[face][:, 2].mean())})
    core = simulator.core  # the throw at action 0, where an untrained policy's mean starts: the faces it lands on
    batch = core.transition(
        core.for_episodes(episodes), np.zeros((n_targets, task_columns.ACTION_SIZE)), simulator.simulator
    )
    landed = task.faces_down(batch.thrown_state[:, layout.ANGLE])
    zero = (np.bincount(landed, minlength=4) / n_targets).tolist()
    rng = np.random.default_rng(seed)
    rows = []
    for start in (0, 2):
        for end in (1, 3):
            repeated = task_config.Episodes(np.repeat(relabelled[end].data, draws, axis=0))
            row: dict[str, Any] = {"start": start, "end": end, "noisy": {}, "targets": {}}
            for sigma in sigmas:
                noise = sigma * rng.standard_normal((n_targets * draws, task_columns.ACTION_SIZE))
                noisy = np.clip(np.repeat(actions[start], draws, axis=0) + noise, -1.0, 1.0)
                stood = simulator.rewards(repeated, noisy)[1].reshape(n_targets, draws)
                row["noisy"][str(sigma)], row["targets"][str(sigma)] = float(stood.mean()), float(stood.any(1).mean())
            rows.append(row)
    line = []
    for alpha in LINE_STEPS:  # the segment from the policy's face-0 throw to its face-2 throw
        throws = (1.0 - alpha) * actions[0] + alpha * actions[2]
        point: dict[Any, Any] = {"alpha": alpha}
        for end in (1, 3):
            reward, success, distance = simulator.rewards(relabelled[end], throws)
            point[end] = {"reward": float(reward.mean()), "success": float(success.mean())}
        point["distance"] = float(np.median(distance))
        line.append(point)
    env.close()
    return {"own": own, "zero": zero, "reach": rows, "line": line}


def checkpoint_policy(run_dir: Path, algo: str, steps: int) -> tuple[TrainedPolicy, np.ndarray]:
    """The policy a run saved after ``steps`` throws (``checkpoints/<algo>_<steps>_steps.zip`` and its
    normalisation statistics) and the standard deviation of its Gaussian per action dimension."""
    folder = Path(run_dir) / "checkpoints"
    model = load_model(algo, folder / f"{algo}_{steps}_steps.zip")
    stats = folder / f"{algo}_vecnormalize_{steps}_steps.pkl"
    vec_normalize = None
    if stats.exists():
        with open(stats, "rb") as file:
            vec_normalize = pickle.load(file)  # the statistics only, as TrainedPolicy.load reads them
    std = np.exp(model.policy.log_std.detach().cpu().numpy())  # type: ignore[union-attr, operator]  # PPO's Gaussian
    return TrainedPolicy(model, vec_normalize), std


def course(run_dir: Path, env_id: str, n_targets: int, steps: list[int], algo: str = "ppo") -> list[dict]:
    """Per checkpoint of a run (after ``steps`` throws): its Gaussian's standard deviation per action dimension and,
    per target face (the first ``n_targets`` test targets made targets of each face in turn), the success of its
    deterministic throw, its mean spin action and the share of those throws that land on face 0."""
    env = gym.make(env_id)
    observations, infos = draw_targets(env, target_seeds(n_targets))
    episodes = oracle.episodes_from_infos(infos)
    simulator = oracle.ThrowSimulator(env, threads=1)
    core = simulator.core
    rows = []
    for step in steps:
        policy, std = checkpoint_policy(run_dir, algo, step)
        row: dict = {"steps": step, "std": std.tolist(), "faces": []}
        for face in range(4):
            obs, relabelled = with_face(observations, episodes, face)
            actions = np.asarray(policy.act(obs, infos, env), dtype=np.float64)
            batch = core.transition(core.for_episodes(relabelled), actions, simulator.simulator)
            success = core.landing(batch)[2]
            landed = task.faces_down(batch.thrown_state[:, layout.ANGLE])
            row["faces"].append(
                {
                    "success": float(success.mean()),
                    "spin": float(actions[:, 2].mean()),
                    "face 0": float((landed == 0).mean()),
                }
            )
        rows.append(row)
    env.close()
    return rows


def course_table(env_id: str, rows: list[dict], n_targets: int, command: str) -> str:
    lines = [
        f"The same run's checkpoints (`{command}`), on the first {n_targets} test targets made targets of each face in "
        "turn: its Gaussian's standard deviation (speed, direction, spin) and per target face the success of its "
        "throw, its mean spin action and (in brackets) the share of throws landing on face 0:",
        "",
        "| throws | std | face 0 | face 1 | face 2 | face 3 |",
        "|---:|---|---|---|---|---|",
    ]
    for row in rows:
        std = ", ".join(f"{value:.3f}" for value in row["std"])
        cells = " | ".join(
            f"{face['success']:.0%}, {face['spin']:+.3f} ({face['face 0']:.0%})" for face in row["faces"]
        )
        lines.append(f"| {row['steps']:,} | {std} | {cells} |")
    return "\n".join(lines)


def reach_table(env_id: str, result: dict[str, list], n_targets: int, draws: int, command: str) -> str:
    sigmas = list(result["reach"][0]["noisy"])
    lines = [
        f"Measured by `{command}` on the first {n_targets} of {env_id}'s test targets, each made a target of every "
        "face in turn. The policy's own deterministic throw per target face:",
        "",
        "| target face | success | mean spin action |",
        "|---|---:|---:|",
    ]
    lines += [f"| face {row['face']} | {row['success']:.1%} | {row['spin']:+.3f} |" for row in result["own"]]
    shares = ", ".join(f"face {face} {share:.1%}" for face, share in enumerate(result["zero"]))
    lines += ["", f"The throw at action 0, where an untrained policy's mean starts, lands on {shares} of the targets."]
    lines += [
        "",
        f"From the policy's throw for a long side, {draws} throws per target with Gaussian noise of standard deviation "
        "sigma per action dimension, scored for a short-end target: the share of throws that stand the box on that "
        "end (in brackets: the share of targets with at least one):",
        "",
        "| from the throw for | stood on | " + " | ".join(f"sigma {s}" for s in sigmas) + " |",
        "|---|---|" + "---:|" * len(sigmas),
    ]
    for row in result["reach"]:
        cells = " | ".join(f"{row['noisy'][s]:.2%} ({row['targets'][s]:.0%})" for s in sigmas)
        lines.append(f"| face {row['start']} | face {row['end']} | {cells} |")
    lines += [
        "",
        "Along the segment from the policy's throw for face 0 (alpha 0) to its throw for face 2 (alpha 1), per target:",
        "",
        "| alpha | median distance | mean reward, face-1 target | stood on face 1 | mean reward, face-3 target | "
        "stood on face 3 |",
        "|---:|---:|---:|---:|---:|---:|",
    ]
    for row in result["line"]:
        lines.append(
            f"| {row['alpha']:.1f} | {row['distance']:.3f} m | {row[1]['reward']:+.2f} | {row[1]['success']:.1%} | "
            f"{row[3]['reward']:+.2f} | {row[3]['success']:.1%} |"
        )
    return "\n".join(lines)


def face_table(env_id: str, rows: list[dict], sigma: float, command: str) -> str:
    lines = [
        f"Measured by `{command}` on the first {sum(row['targets'] for row in rows)} of {env_id}'s test targets: "
        "the oracle's solutions in ballistic commands mapped to the env's actions; per target face, each action "
        f"dimension's range over them and the success of throws at them plus noise of sigma {sigma} in the env's "
        "actions:",
        "",
        f"| target face | targets | solved | speed | direction | spin | sigma {sigma} |",
        "|---|---:|---:|---|---|---|---:|",
    ]
    for row in rows:
        if row["solved"] == 0:
            lines.append(f"| face {row['face']} | {row['targets']} | 0 | - | - | - | - |")
            continue
        ranges = " | ".join(f"{lo:+.2f} to {hi:+.2f}" for lo, hi in zip(row["low"], row["high"], strict=True))
        lines.append(f"| face {row['face']} | {row['targets']} | {row['solved']} | {ranges} | {row['noisy']:.1%} |")
    return "\n".join(lines)


def table(results: list[dict], command: str) -> str:
    sigmas = list(results[0]["spaces"]["env actions"]["noisy"])
    lines = [
        f"Measured by `{command}`: the oracle's solution per target (the targets it solved), then "
        f"{results[0]['draws']} throws per target at it plus Gaussian noise of standard deviation sigma per "
        "dimension, in the space the agent acts in (both spaces are [-1, 1]^3):",
        "",
        "| variant | acting in | oracle solved | " + " | ".join(f"sigma {s}" for s in sigmas) + " |",
        "|---|---|---:|" + "---:|" * len(sigmas),
    ]
    for result in results:
        for name, space in result["spaces"].items():
            lines.append(
                f"| {result['env_id']} | {name} | {space['solved']:.1%} of {result['targets']} | "
                + " | ".join(f"{space['noisy'][s]:.1%}" for s in sigmas)
                + " |"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m agents.raw_actions", description=__doc__.split("\n\n")[0])
    parser.add_argument("--envs", nargs="+", default=list(ENVS))
    parser.add_argument("--targets", type=int, default=64)
    parser.add_argument("--draws", type=int, default=32, help="noisy throws per target and sigma")
    parser.add_argument("--readme", action="store_true", help="write the table into docs/methodology/raw-actions.md")
    parser.add_argument(
        "--by-face",
        action="store_true",
        help="instead: per target face, where the throws that stand the box on it lie in the env's actions (one "
        "face variant in --envs)",
    )
    parser.add_argument(
        "--reach",
        type=Path,
        metavar="RUN",
        help="instead: from RUN's trained throws for the long sides, how often Gaussian exploration stands the box "
        "on each short end (one face variant in --envs)",
    )
    parser.add_argument(
        "--steps",
        type=int,
        nargs="+",
        metavar="N",
        help="with --reach: also the same per-face throws of RUN's checkpoints after N throws (checkpoints/)",
    )
    args = parser.parse_args(argv)
    if args.steps and not args.reach:
        parser.error("--steps goes with --reach RUN")
    for env_id in args.envs:
        if env_id not in gym.registry or env_id.startswith("BoxToss-Stack"):
            parser.error(f"--envs: {env_id!r} is not a registered one-throw BoxToss variant")
    if args.targets < 1 or args.draws < 1:
        parser.error("--targets and --draws must be integers >= 1")
    if args.by_face or args.reach:
        if len(args.envs) != 1 or gym.spec(args.envs[0]).kwargs.get("target_face") != "exact":
            option = "--by-face" if args.by_face else "--reach"
            parser.error(f"{option}: --envs takes one variant whose targets name one face (BoxToss-ThisSideUp-v0)")
    if args.reach:
        policy, _ = load_policy(args.reach, "final")
        steps = f" --steps {' '.join(str(step) for step in args.steps)}" if args.steps else ""
        command = (
            f"python -m agents.raw_actions --reach {args.reach} --envs {args.envs[0]} --targets {args.targets} "
            f"--draws {args.draws}{steps} --readme"
        )
        result = reach(policy, args.envs[0], args.targets, args.draws)
        text = reach_table(args.envs[0], result, args.targets, args.draws, command)
        if args.steps:
            steps = " ".join(str(step) for step in args.steps)
            text += "\n\n" + course_table(
                args.envs[0],
                course(args.reach, args.envs[0], args.targets, args.steps),
                args.targets,
                f"--steps {steps}",
            )
        print(text)
        if args.readme:
            replace_section("raw-face-reach", text)
        return
    if args.by_face:
        command = (
            f"python -m agents.raw_actions --by-face --envs {args.envs[0]} --targets {args.targets} --draws "
            f"{args.draws} --readme"
        )
        text = face_table(args.envs[0], by_face(args.envs[0], args.targets, args.draws), 0.01, command)
        print(text)
        if args.readme:
            replace_section("raw-faces", text)
        return
    results = [measure(env_id, args.targets, args.draws) for env_id in args.envs]
    command = (
        f"python -m agents.raw_actions --envs {' '.join(args.envs)} --targets {args.targets} --draws "
        f"{args.draws} --readme"
    )
    text = table(results, command)
    print(text)
    if args.readme:
        replace_section("raw-actions", text)


if __name__ == "__main__":
    main()
