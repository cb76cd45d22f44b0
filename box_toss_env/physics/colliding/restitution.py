"""The restitution stage of the colliding solver (``stages.COLLIDING_SUBSTEP``): the impacts' targets
u_rel . n >= -e u0 polished contact by contact after the joint solve (``apply_restitution``), and the contacts
its sweeps left short of their targets held (``hold_targets``).
"""

from ..compile.compilation import jit_stage
from ..tunables import EXACT_CONVERGED, HOLD_ROUNDS, RESTITUTION_ITERATIONS
from .parallel import PARALLEL_CONTACTS, partitioned_hold, partitioned_restitution
from .prepare import is_impact_contact, restitution_step, short_of_target


@jit_stage
def apply_restitution(contacts, count, bodies, threshold, moved):
    """Stage 5's polish, after the impacts were solved with every contact and friction: contact by contact,
    u_rel . n >= -e u0 for the contacts that approached faster than the threshold and took an impulse (the
    normal impulse stays >= 0; a single contact gets the closed form to rounding); every other contact joins with
    its speculative target less the threshold, its impulse only growing (with the floor's alone, a box spun by an
    impact at one corner turned into the box it lay on: 6.6 mm deep in a dropped pile of 16). Returns how many
    contacts are impacts. From PARALLEL_CONTACTS contacts up block by block, on threads
    (``parallel.partitioned_restitution``). Then the contacts its sweeps left short (``hold_targets``; ``moved``:
    (2, bodies) work)."""
    if count >= PARALLEL_CONTACTS:
        impacts = partitioned_restitution(contacts, count, bodies, threshold)
        if impacts > 0:
            hold_targets(contacts, count, bodies, threshold, moved)
        return impacts
    rows, ids = contacts.rows, contacts.ids
    vel, inv_mass, inv_inertia = bodies.vel, bodies.inv_mass, bodies.inv_inertia
    impacts = 0
    for c in range(count):
        if is_impact_contact(c, rows, threshold):
            impacts += 1
    if impacts == 0:
        return 0
    for _ in range(RESTITUTION_ITERATIONS):
        change = 0.0
        total = 0.0
        for c in range(count):
            dp, after = restitution_step(c, rows, ids, vel, inv_mass, inv_inertia, threshold)
            change += dp
            total += after
        if change <= EXACT_CONVERGED * total:
            break
    hold_targets(contacts, count, bodies, threshold, moved)
    return impacts


@jit_stage
def hold_targets(contacts, count, bodies, threshold, moved):
    """After the polish's sweeps: each contact still approaching faster than its polish target by more than the
    threshold (``polish_target``: the sweeps ended before they converged) takes the polish's step again, contact by
    contact, only those, round after round until none does (at most HOLD_ROUNDS rounds). A corner left approaching
    at u_rel . n below its target closes its gap by the difference times h: in a dropped pile of 1,000, the polish's
    16 sweeps left a box's corner 1.4 m/s into the box below, 3.8 mm deep in one substep of 1/256 s. A round that
    finds none costs one pass over the contacts; the rounds visit only the contacts short of their targets. From
    PARALLEL_CONTACTS contacts up block by block, on threads, in ``moved`` ((2, bodies) work) the bodies each round
    stepped (``parallel.partitioned_hold``)."""
    if count >= PARALLEL_CONTACTS:
        partitioned_hold(contacts, bodies, threshold, moved)
        return
    rows, ids = contacts.rows, contacts.ids
    vel, inv_mass, inv_inertia = bodies.vel, bodies.inv_mass, bodies.inv_inertia
    for _ in range(HOLD_ROUNDS):
        held = 0
        for c in range(count):
            if short_of_target(c, rows, ids, vel, threshold):
                restitution_step(c, rows, ids, vel, inv_mass, inv_inertia, threshold)
                held += 1
        if held == 0:
            return
