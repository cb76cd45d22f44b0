"""The stage script of the robust solvers, written once: every stage's name and what it does (``STAGES``), and each
solver's script as the names of the stages it runs, in its order (``COLLIDING_STEP``, ``COLLIDING_SUBSTEP``,
``FLOOR_STEP``, ``FLOOR_PIECE``).

The code that runs a script names each stage it runs in a comment that starts with the stage's name, in the script's
order (``colliding.step.substep``, ``robust.contact_step.contact_step`` with ``solve_piece``;
``tests/physics/test_stages.py`` checks it), and docs/box_collisions.md shows the scripts as ``scripts_markdown``
writes them (``python -m box_toss_env.physics.stages`` prints it; the same test checks the docs hold it). A stage's
formulas and tiers are its module's docstring (``colliding.solve``, ``robust.contact_solver``, ...).

Both solvers use the same names; their orders differ in two places, each for its physics. Restitution: the
floor-only solver locates an impact in time and resolves it at that instant, before the piece it opens (Poisson's
law on the compression impulse, which never creates energy with friction); the colliding solver resolves impacts in
the substep their gap closes, after the resting solve, and solves them again with every other contact (Newton's
law). Relax: the floor-only solver corrects what the step left penetrating, after the positions; the colliding
solver corrects the penetration of the contacts it has just found, island by island, before the velocities. Either
move changes every trajectory (the penalty then acts on other positions), so each solver keeps its order.
"""

from typing import NamedTuple


class Stage(NamedTuple):
    name: str
    does: str


STAGES = {
    stage.name: stage
    for stage in (
        Stage("wake", "every sleeping island an awake body can reach within the step wakes"),
        Stage(
            "alone",
            "while few bodies are awake and no two can meet, whole steps of each awake body alone against the floor "
            "(the floor-only solver's script)",
        ),
        Stage(
            "quiet",
            "every awake body slower than the sleep speed at every point: 4 grid steps taken as one step (a resting "
            "scene kept awake costs about a quarter, as still)",
        ),
        Stage("groups", "bodies that cannot meet within the step take substep counts of their own"),
        Stage(
            "flight",
            "no contact: the exact parabola, up to the first instant a corner reaches the floor (conservative "
            "advancement), where restitution opens a contact step",
        ),
        Stage(
            "substeps",
            "the step cut so that no point moves further than a share of the thinnest box, nor any box turns "
            "further than a limit, in one substep (no tunnelling)",
        ),
        Stage(
            "find contacts",
            "the contacts each body can close within the substep (speculative), with their normal velocities",
        ),
        Stage(
            "relax",
            "penetration beyond the slop removed by the critically damped penalty spring, implicit, as a "
            "pseudo-velocity: positions move, velocities do not",
        ),
        Stage("integrate velocities", "v += h g"),
        Stage("warm start", "each contact starts from its impulses of the last substep (or a resting pile's guess)"),
        Stage(
            "solve contacts",
            "normal impulses p >= 0 that let each gap close but not pass (u_n >= -max(gap, 0) / h), friction "
            "abs(q) <= mu p that never reverses a slip (the contact law)",
        ),
        Stage("store impulses", "the impulses kept for the next substep's warm start, or the corners that held"),
        Stage(
            "restitution",
            "an impact (approach faster than the restitution threshold) bounces: u_n+ = -e u_n- (Newton) or e "
            "times its compression impulse (Poisson)",
        ),
        Stage(
            "locate impacts",
            "a corner stopped while approaching faster than the threshold would hit inside the step: the piece "
            "ends at its arrival and restitution resolves it there",
        ),
        Stage("energy limit", "the velocities scaled by the one s in [0, 1] that gains no kinetic + potential energy"),
        Stage(
            "integrate positions",
            "x += h v (symplectic Euler); out of contact the exact parabola x += h v - h^2 g / 2",
        ),
        Stage("sleep", "a body (an island) still for the sleep time sleeps: no cost until touched"),
    )
}
"""Every stage of the robust solvers by name."""

COLLIDING_STEP = ("wake", "alone", "quiet", "groups", "substeps", "sleep")
"""A grid step of the colliding solver (``colliding.kernel.advance_steps``, ``colliding.step.advance_step``)."""

COLLIDING_SUBSTEP = (
    "find contacts",
    "relax",
    "integrate velocities",
    "warm start",
    "solve contacts",
    "store impulses",
    "restitution",
    "energy limit",
    "integrate positions",
)
"""A substep of the colliding solver (``colliding.step.substep``)."""

FLOOR_STEP = ("flight", "substeps", "sleep")
"""A grid step of the floor-only solver (``robust.robust_solver.advance_box``): in flight no step at all; in contact
substeps where the box turns fast, each cut into pieces at the impacts located inside it."""

FLOOR_PIECE = (
    "restitution",
    "find contacts",
    "integrate velocities",
    "solve contacts",
    "locate impacts",
    "store impulses",
    "energy limit",
    "integrate positions",
    "relax",
)
"""A piece of a contact step of the floor-only solver (``robust.contact_step.contact_step``, ``solve_piece``)."""

SCRIPTS = {
    "colliding solver, a grid step": COLLIDING_STEP,
    "colliding solver, a substep": COLLIDING_SUBSTEP,
    "floor-only solver, a grid step": FLOOR_STEP,
    "floor-only solver, a piece of a substep": FLOOR_PIECE,
}


def scripts_markdown() -> str:
    """The scripts as a Markdown table: a row a stage, with its place in each script (a description holds no
    ``|``)."""
    header = "| stage | what it does | " + " | ".join(SCRIPTS) + " |"
    rule = "|---|---|" + "---:|" * len(SCRIPTS)
    rows = [
        f"| {name} | {stage.does} | "
        + " | ".join(str(script.index(name) + 1) if name in script else "" for script in SCRIPTS.values())
        + " |"
        for name, stage in STAGES.items()
    ]
    return "\n".join([header, rule, *rows]) + "\n"


if __name__ == "__main__":
    print(scripts_markdown(), end="")
