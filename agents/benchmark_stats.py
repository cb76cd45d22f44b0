"""The benchmark's statistics, with ``rliable`` (Agarwal et al., NeurIPS 2021): interquartile means with
stratified-bootstrap 95% confidence intervals, the probability of improvement, and performance profiles.

A run's score is its success rate on the test targets (episodes for ``BoxToss-Stack-v0``), divided by the variant's
ceiling where scores of several variants are pooled (the aggregate, the probability of improvement and the
profiles: ``normalised``). rliable works on a matrix of runs x tasks; a cell of the table is one task, the aggregate
over variants all of them, with the same number of runs on each (``rectangular``: the first seeds of each, as many as
the variant with the fewest has). Every bootstrap draws ``REPS`` resamples from a fixed random state, so the same
runs give the same intervals.
"""

from __future__ import annotations

import contextlib
import textwrap
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from agents.report import pyplot

REPS = 5_000
"""Bootstrap resamples of an interval (rliable's default is 50,000; 5,000 moves an interval's ends by well under
a percent, and a table of some 70 cells is written in under a minute)."""
IMPROVEMENT_REPS = 1_000
"""Resamples of a probability of improvement (rliable's is a Python loop over pairs of runs: about 2.5 s per 100)."""
SEED = 0
TAUS = np.linspace(0.0, 1.0, 101)
"""Thresholds of the performance profiles: the share of runs whose normalised score exceeds tau."""
PANEL_TITLE_WIDTH = 40
"""Characters in a line of a panel's title (a panel is 5.2 inches wide; a longer title ran past the figure)."""


@dataclass(frozen=True)
class Estimate:
    """A point estimate with its 95% confidence interval and the number of runs (and tasks) behind it."""

    value: float
    low: float
    high: float
    runs: int

    def percent(self) -> str:
        """``70.2% [64.9, 75.5] (5)``: the value, the interval's ends in percent, the runs."""
        return f"{self.value:.1%} [{100 * self.low:.1f}, {100 * self.high:.1f}] ({self.runs})"

    def probability(self) -> str:
        """``0.62 [0.41, 0.80]``."""
        return f"{self.value:.2f} [{self.low:.2f}, {self.high:.2f}]"


def _random_state() -> np.random.RandomState:
    return np.random.RandomState(SEED)


@contextlib.contextmanager
def fixed_draws():
    """rliable's stratified bootstrap draws its resamples from numpy's global random state (besides the one it is
    given): seeded with ``SEED`` inside, as it was outside afterwards; arch's notice that ``random_state`` is
    deprecated is silenced."""
    saved = np.random.get_state()  # noqa: NPY002  (rliable draws from the legacy global state)
    np.random.seed(SEED)  # noqa: NPY002
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="random_state is deprecated", category=FutureWarning)
            yield
    finally:
        np.random.set_state(saved)  # noqa: NPY002


def iqm(scores: np.ndarray) -> Estimate:
    """The interquartile mean of ``scores`` (runs x tasks, or runs) and its stratified-bootstrap 95% interval."""
    from rliable import library, metrics

    matrix = np.asarray(scores, dtype=np.float64)
    matrix = matrix[:, None] if matrix.ndim == 1 else matrix
    with fixed_draws():
        point, interval = library.get_interval_estimates(
            {"x": matrix},
            lambda x: np.array([metrics.aggregate_iqm(x)]),
            reps=REPS,
            random_state=_random_state(),
        )
    low, high = interval["x"][:, 0]
    return Estimate(float(point["x"][0]), float(low), float(high), matrix.shape[0])


def probability_of_improvement(x: np.ndarray, y: np.ndarray) -> Estimate:
    """P(X > Y): the probability that a run of X scores above a run of Y on a task drawn at random (ties count half),
    averaged over tasks, with its stratified-bootstrap 95% interval; ``x`` and ``y`` are runs x tasks (the same
    tasks, any numbers of runs)."""
    from rliable import library, metrics

    with fixed_draws():
        point, interval = library.get_interval_estimates(
            {"pair": (np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))},
            metrics.probability_of_improvement,
            reps=IMPROVEMENT_REPS,
            random_state=_random_state(),
        )
    low, high = interval["pair"][:, 0] if interval["pair"].ndim == 2 else interval["pair"]
    return Estimate(float(point["pair"]), float(low), float(high), int(np.shape(x)[0]))


def rectangular(columns: list[list[float]]) -> np.ndarray | None:
    """A runs x tasks matrix of per-task score lists: the first ``min(len)`` runs of each (None if a task has none)."""
    if not columns or min(len(column) for column in columns) == 0:
        return None
    runs = min(len(column) for column in columns)
    return np.array([column[:runs] for column in columns], dtype=np.float64).T


def profiles(matrices: dict[str, np.ndarray]) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Performance profiles at ``TAUS``: per agent the share of (run, task) scores above each tau, and its
    stratified-bootstrap 95% band (2 x len(TAUS))."""
    from rliable import library

    # rliable's create_performance_profile with a fixed random state (it takes none): the same bands every time
    with fixed_draws():
        return library.get_interval_estimates(
            matrices,
            lambda scores: library.score_distributions(scores, TAUS),
            reps=REPS // 5,
            random_state=_random_state(),
        )


def panel_title(title: str) -> str:
    """A panel's title in lines that fit its width (a long one ran past the figure's edge)."""
    return "\n".join(textwrap.wrap(title, PANEL_TITLE_WIDTH))


def plot_profiles(panels: dict[str, dict[str, np.ndarray]], path: Path, colors: dict[str, str]) -> Path | None:
    """One panel per tier (``panels``: title -> agent -> runs x tasks of normalised scores): the performance
    profile of each agent with its band (rliable's ``plot_performance_profiles``), written to ``path``."""
    from rliable import plot_utils

    from box_toss_env.files import save_figure

    shown = {title: matrices for title, matrices in panels.items() if matrices}
    if not shown:
        return None
    plt = pyplot()
    fig, axes = plt.subplots(1, len(shown), figsize=(5.2 * len(shown), 3.8), squeeze=False)
    for ax, (title, matrices) in zip(axes[0], shown.items(), strict=True):
        points, bands = profiles(matrices)
        plot_utils.plot_performance_profiles(
            points,
            TAUS,
            performance_profile_cis=bands,
            colors={agent: colors[agent] for agent in matrices},
            xlabel=r"normalised score $\tau$ (success / ceiling)",
            ylabel=r"share of runs with score > $\tau$",
            labelsize="medium",
            ticklabelsize="small",
            ax=ax,
            legend=True,
            legendsize="small",
        )
        ax.set_title(panel_title(title), fontsize="medium")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path


def plot_aggregates(panels: dict[str, dict[str, Estimate]], path: Path, colors: dict[str, str]) -> Path | None:
    """One panel per tier: each agent's IQM of normalised scores over the variants, with its 95% interval."""
    from box_toss_env.files import save_figure

    shown = {title: estimates for title, estimates in panels.items() if estimates}
    if not shown:
        return None
    plt = pyplot()
    rows = max(len(estimates) for estimates in shown.values())
    fig, axes = plt.subplots(1, len(shown), figsize=(5.2 * len(shown), 0.45 * rows + 1.2), squeeze=False)
    for ax, (title, estimates) in zip(axes[0], shown.items(), strict=True):
        names = list(estimates)[::-1]
        for k, name in enumerate(names):
            e = estimates[name]
            ax.barh(k, e.high - e.low, left=e.low, height=0.6, color=colors[name], alpha=0.75)
            ax.vlines(e.value, k - 0.3, k + 0.3, color="k", linewidth=2)
        ax.set_yticks(range(len(names)), names)
        ax.set(xlim=(0, 1.02), xlabel="IQM of success / ceiling, over variants (95% CI)", title=panel_title(title))
        ax.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path
