"""Stage restitution of the colliding solver (stage 5 of ``step``'s script): the impacts' targets
u_rel . n >= -e u0 polished contact by contact after the joint solve (``apply_restitution``).
"""

from ..compile.compilation import jit_stage
from .limits import CONVERGED, RESTITUTION_ITERATIONS
from .narrowphase import APPROACH, BODY2, IMPULSE, NORMAL_MASS, NX, NY, RESTITUTION, TARGET
from .prepare import apply_impulse, relative_velocity


@jit_stage
def apply_restitution(contacts, ids, count, vel, inv_mass, inv_inertia, threshold):
    """Stage 5's polish, after the impacts were solved with every contact and friction: contact by contact,
    u_rel . n >= -e u0 for the contacts that approached faster than the threshold and took an impulse (the
    normal impulse stays >= 0; a single contact gets the closed form to rounding); the floor's other contacts
    join with their speculative target less the threshold, their impulse only growing. Returns how many
    contacts are impacts."""
    impacts = 0
    for c in range(count):
        if contacts[c, APPROACH] < -threshold and contacts[c, IMPULSE] > 0.0:
            impacts += 1
    if impacts == 0:
        return 0
    for _ in range(RESTITUTION_ITERATIONS):
        change = 0.0
        total = 0.0
        for c in range(count):
            if contacts[c, APPROACH] < -threshold and contacts[c, IMPULSE] > 0.0:
                target = -contacts[c, RESTITUTION] * contacts[c, APPROACH]
                least = 0.0
            elif ids[c, BODY2] < 0:  # the floor's other contacts: an impact may not drive a corner into the
                target = contacts[c, TARGET] - threshold  # floor faster than the threshold, nor release it
                least = contacts[c, IMPULSE]
            else:
                continue
            nx, ny = contacts[c, NX], contacts[c, NY]
            ux, uy = relative_velocity(c, contacts, ids, vel)
            before = contacts[c, IMPULSE]
            after = max(before - (ux * nx + uy * ny - target) * contacts[c, NORMAL_MASS], least)
            contacts[c, IMPULSE] = after
            dp = after - before
            if dp != 0.0:
                apply_impulse(c, dp * nx, dp * ny, contacts, ids, vel, inv_mass, inv_inertia)
            change += abs(dp)
            total += after
        if change <= CONVERGED * total:
            break
    return impacts
