"""The colliding solver's limits and tolerances, shared by its stages.
"""

from .joint_contact_solve import HISTORY, JOINT_ROUNDS

TUNNEL_FRACTION = 0.5  # [-] of the smallest half extent: the most any point moves in one substep
MAX_SUBSTEPS = 256
VELOCITY_ITERATIONS = 64  # rounds of exact normal solve and friction sweep at most per substep
RESTITUTION_ITERATIONS = 16
PENALTY_ITERATIONS = 16  # the penalty's Gauss-Seidel sweeps at most (fewer if the scene's solver_iterations is)
CONVERGED = 1e-9  # sweeps stop when the impulses change by less than this share of their sum
SINGLE_CHANGE = 100.0  # [-] and none by more than this many times that share of their mean (``gauss_seidel``)
CONTACT_TOLERANCE = 1e-12  # [m per m of size + 1 m] penetration below this is not corrected
MIN_CAPACITY = 16
DIRECT_LIMIT = 64  # contacts: up to this many, the normal impulses are solved exactly (``normal_lcp``)
assert DIRECT_LIMIT >= HISTORY + JOINT_ROUNDS  # the solves' ``index`` also holds ``joint_impulses``'s rounds
REGULARISATION = 1e-12  # share of W_cc added to the diagonal of the exact solve (redundant contacts)
LCP_TOLERANCE = 1e-12  # share of the largest |free velocity|: a contact left free may approach by this much
SUPPORT_SLOPE = 0.5  # [-] |n_y| above which a contact carries weight in a cold start's guess (``resting_loads``)
ALONE_LIMIT = 8  # awake bodies at most for which whole steps alone against the floor are looked for (steps_alone)
SPLIT_SAVING = 64  # body-substeps a step at least that substeps per group must save, else one count (``groups``)
SOLVE_SHARE = 4  # [-] a body's substep in a pile costs about this many times a pass of a substep's loops over it
ALONE_LOWEST = 0.5  # [share of the smaller half extent] a box's centre is taken never to sink below this height
