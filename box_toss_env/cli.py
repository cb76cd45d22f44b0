"""``box-toss``: one console command for BoxToss's programs, a thin dispatch to their modules.

    box-toss train ...         python -m agents.train ...
    box-toss evaluate RUN ...  python -m agents.evaluate RUN ...
    box-toss main ...          python -m agents.main ...
    box-toss view ...          python -m box_toss_env.viewer ...
    box-toss bench NAME ...    python -m benchmarks.NAME ...

Each subcommand runs its module in this Python with the remaining arguments unchanged, so
``box-toss SUBCOMMAND --help`` is the module's own help, listing every option. ``agents`` and
``benchmarks`` are not installed with the package: run those subcommands from the repository's root
(as ``python -m agents.main`` is).
"""

from __future__ import annotations

import importlib.util
import os
import sys

COMMANDS = {
    "train": ("agents.train", "train one agent (hyperparameters from agents/hyperparams/<algo>.yml)"),
    "evaluate": ("agents.evaluate", "evaluate a run folder on the fixed test targets: tables, plots, a GIF"),
    "main": ("agents.main", "train PPO on BoxToss-ThisSideUp-v0 and print it beside random throws and the oracle"),
    "view": ("box_toss_env.viewer", "the interactive viewer and play mode (needs the render extra)"),
    "bench": ("benchmarks.NAME", "a benchmark: box-toss bench NAME [options], NAME one of those below"),
}
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
    lines += [f"  {name:<{width}}  {text} (python -m {module})" for name, (module, text) in COMMANDS.items()]
    lines += ["", "benchmarks (box-toss bench NAME --help):"]
    lines += [f"  {name:<14}  {text}" for name, text in BENCHMARKS.items()]
    return "\n".join(lines)


def module_for(argv: list[str]) -> tuple[str, list[str]]:
    """The module a command line runs and the arguments passed on to it (SystemExit with the usage if none)."""
    if not argv or argv[0] in ("-h", "--help"):
        print(usage())
        raise SystemExit(0 if argv else 2)
    command, rest = argv[0], argv[1:]
    if command not in COMMANDS:
        print(usage(), file=sys.stderr)
        raise SystemExit(f"box-toss: unknown subcommand {command!r}")
    if command != "bench":
        return COMMANDS[command][0], rest
    if not rest or rest[0] in ("-h", "--help"):
        print("usage: box-toss bench {" + ",".join(BENCHMARKS) + "} [options]\n")
        print("\n".join(f"  {name:<14}  {text}" for name, text in BENCHMARKS.items()))
        raise SystemExit(0 if rest else 2)
    if rest[0] not in BENCHMARKS:
        raise SystemExit(f"box-toss bench: unknown benchmark {rest[0]!r}, one of {', '.join(BENCHMARKS)}")
    return f"benchmarks.{rest[0]}", rest[1:]


def main(argv: list[str] | None = None) -> None:
    module, rest = module_for(list(sys.argv[1:] if argv is None else argv))
    sys.path.insert(0, os.getcwd())  # python -m finds agents/ and benchmarks/ in the current directory
    if importlib.util.find_spec(module.split(".")[0]) is None:
        raise SystemExit(
            f"box-toss: {module} not found: run this subcommand from the repository's root "
            "(agents/ and benchmarks/ are not installed with the package)"
        )
    os.execv(sys.executable, [sys.executable, "-m", module, *rest])


if __name__ == "__main__":
    main()
