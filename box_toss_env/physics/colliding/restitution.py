"""The restitution stage of the colliding solver (``stages.COLLIDING_SUBSTEP``): the impacts' targets
u_rel . n >= -e u0 polished contact by contact after the joint solve (``apply_restitution``).
"""

from ..compile.compilation import jit_stage
from ..contact_law import is_impact
from ..tunables import EXACT_CONVERGED, RESTITUTION_ITERATIONS
from .narrowphase import APPROACH, IMPULSE
from .parallel import PARALLEL_CONTACTS, partitioned_restitution
from .prepare import restitution_step


@jit_stage
def apply_restitution(contacts, count, bodies, threshold):
    """Stage 5's polish, after the impacts were solved with every contact and friction: contact by contact,
    u_rel . n >= -e u0 for the contacts that approached faster than the threshold and took an impulse (the
    normal impulse stays >= 0; a single contact gets the closed form to rounding); every other contact joins with
    its speculative target less the threshold, its impulse only growing (with the floor's alone, a box spun by an
    impact at one corner turned into the box it lay on: 6.6 mm deep in a dropped pile of 16). Returns how many
    contacts are impacts. From PARALLEL_CONTACTS contacts up block by block, on threads
    (``parallel.partitioned_restitution``)."""
    if count >= PARALLEL_CONTACTS:
        return partitioned_restitution(contacts, count, bodies, threshold)
    rows, ids = contacts.rows, contacts.ids
    vel, inv_mass, inv_inertia = bodies.vel, bodies.inv_mass, bodies.inv_inertia
    impacts = 0
    for c in range(count):
        if is_impact(rows[c, APPROACH], threshold) and rows[c, IMPULSE] > 0.0:
            impacts += 1
    if impacts == 0:
        return 0
    for _ in range(RESTITUTION_ITERATIONS):
        change = 0.0
        total = 0.0
        for c in range(count):
            moved, after = restitution_step(c, rows, ids, vel, inv_mass, inv_inertia, threshold)
            change += moved
            total += after
        if change <= EXACT_CONVERGED * total:
            break
    return impacts
