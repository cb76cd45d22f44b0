"""``box-toss``: one console command for BoxToss's programs, a thin dispatch to their modules.

    box-toss train ...         train PPO, SAC or TD3 on a BoxToss env into runs/NAME (python -m agents.train)
    box-toss evaluate RUN ...  evaluate a run folder on the fixed test targets (python -m agents.evaluate)
    box-toss main ...          train PPO and print it beside random throws and the oracle (python -m agents.main)
    box-toss view ...          the interactive viewer and play mode (python -m box_toss_env.viewer)
    box-toss bench NAME ...    a benchmark of a clone of the repository (python -m benchmarks.NAME)

Each subcommand runs its module's ``main`` in this Python with the remaining arguments unchanged, so
``box-toss SUBCOMMAND --help`` is the module's own help, listing every option. ``train``, ``evaluate`` and
``main`` are installed with the package (``agents``, with its hyperparameter files) and need the ``train``
extra; ``view`` needs the ``render`` extra; the benchmarks are the repository's (``benchmarks/``, not
installed): ``bench`` runs them from a clone's root. A missing extra is one line naming it. Nothing heavy is
imported before a subcommand parses its options, so ``--help`` answers at once.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys

COMMANDS = {
    "train": ("agents.train", "train one agent (hyperparameters from agents/hyperparams/<algo>.yml)"),
    "evaluate": ("agents.evaluate", "evaluate a run folder on the fixed test targets: tables, plots, a GIF"),
    "main": ("agents.main", "train PPO on BoxToss-ThisSideUp-v0 and print it beside random throws and the oracle"),
    "view": ("box_toss_env.viewer", "the interactive viewer and play mode (needs the render extra)"),
    "bench": ("benchmarks.NAME", "a benchmark of a clone: box-toss bench NAME [options], NAME one of those below"),
}
EXTRAS = {
    "train": ("train", {"stable_baselines3": "stable-baselines3", "torch": "torch", "yaml": "pyyaml"}),
    "evaluate": ("train", {"stable_baselines3": "stable-baselines3", "torch": "torch", "yaml": "pyyaml"}),
    "main": ("train", {"stable_baselines3": "stable-baselines3", "torch": "torch", "yaml": "pyyaml"}),
    "view": ("render", {"pygame": "pygame-ce"}),
}
"""The extra each subcommand needs, and the modules (with their packages' names) that tell whether it is there."""
BENCHMARKS = {
    "engine": "ns per body-step and us per throw of the engine (docs/methodology/engine-benchmark.md)",
    "throughput": "throws per second of the env, single and batched, and of other engines (docs/throughput.md)",
    "cold_start": "the first throw in a fresh interpreter, cold and warm cache (docs/cold-start.md)",
    "env_throughput": "throws per second of one env id, single and batched",
    "rllib_sampling": "RLlib's sampling speed, native batched env against its default (rllib extra)",
}


def usage() -> str:
    width = max(map(len, COMMANDS))
    lines = [
        "usage: box-toss {" + ",".join(COMMANDS) + "} [options]",
        "",
        __doc__.split("\n\n")[0],
        "",
        "subcommands (box-toss SUBCOMMAND --help lists every option):",
    ]
    lines += [f"  {name:<{width}}  {text}" for name, (module, text) in COMMANDS.items()]
    lines += ["", "benchmarks (box-toss bench NAME --help; run from a clone's root):"]
    lines += [f"  {name:<14}  {text}" for name, text in BENCHMARKS.items()]
    return "\n".join(lines)


def module_for(argv: list[str]) -> tuple[str, str, list[str]]:
    """(the module a command line runs, its program name, the arguments passed on to it); SystemExit with the
    usage if none."""
    if not argv or argv[0] in ("-h", "--help"):
        print(usage())
        raise SystemExit(0 if argv else 2)
    if argv[0] == "--version":
        from box_toss_env import __version__

        print(f"box-toss {__version__}")
        raise SystemExit(0)
    command, rest = argv[0], argv[1:]
    if command not in COMMANDS:
        print(usage(), file=sys.stderr)
        raise SystemExit(f"box-toss: unknown subcommand {command!r}")
    if command != "bench":
        return COMMANDS[command][0], f"box-toss {command}", rest
    if not rest or rest[0] in ("-h", "--help"):
        print("usage: box-toss bench {" + ",".join(BENCHMARKS) + "} [options]  (from a clone's root)\n")
        print("\n".join(f"  {name:<14}  {text}" for name, text in BENCHMARKS.items()))
        raise SystemExit(0 if rest else 2)
    if rest[0] not in BENCHMARKS:
        raise SystemExit(f"box-toss bench: unknown benchmark {rest[0]!r}, one of {', '.join(BENCHMARKS)}")
    return f"benchmarks.{rest[0]}", f"box-toss bench {rest[0]}", rest[1:]


def missing_extra(command: str) -> str | None:
    """The one line saying which extra ``command`` needs, if a package of it is not installed (else None)."""
    if command not in EXTRAS:
        return None
    extra, modules = EXTRAS[command]
    missing = [package for module, package in modules.items() if importlib.util.find_spec(module) is None]
    if not missing:
        return None
    return (
        f"box-toss {command}: needs {', '.join(missing)}, which the {extra} extra installs: "
        f"pip install 'box_toss_env[{extra}]'"
    )


def main(argv: list[str] | None = None) -> None:
    argv = list(sys.argv[1:] if argv is None else argv)
    module, prog, rest = module_for(argv)
    if (message := missing_extra(argv[0])) is not None:
        raise SystemExit(message)
    if module.startswith("benchmarks."):
        sys.path.insert(0, os.getcwd())  # a clone's root holds benchmarks/
        if importlib.util.find_spec("benchmarks") is None:
            raise SystemExit(
                f"{prog}: the benchmarks are the repository's (benchmarks/ in a clone of box_toss_env), not "
                "installed with the package: run box-toss bench from the clone's root"
            )
    sys.argv = [prog, *rest]  # a parser without its own prog names itself after argv[0]: "box-toss ..."
    target = importlib.import_module(module + (".__main__" if module == "box_toss_env.viewer" else ""))
    status = target.main()
    raise SystemExit(status if isinstance(status, int) else 0)


if __name__ == "__main__":
    main()
