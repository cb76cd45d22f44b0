"""Column layouts of the flat float64 arrays that cross the Python/numba boundary.

Kernels receive a few 2-D arrays instead of dozens of arguments (each argument costs
dispatch time); these named columns keep both sides readable. Module-level ints are
compile-time constants inside numba kernels.
"""

# state (n_bodies, STATE_SIZE): the pose and velocity of each box's centre of mass
X, Y, ANGLE, VX, VY, SPIN = 0, 1, 2, 3, 4, 5  # [m], [m], [rad], [m/s], [m/s], [rad/s]
STATE_SIZE = 6

# body parameters (n_bodies, PARAM_SIZE): geometry, inertia and the floor contact material
HALF_LENGTH, HALF_WIDTH, MASS, INERTIA, RESTITUTION, FRICTION, STIFFNESS = 0, 1, 2, 3, 4, 5, 6
PARAM_SIZE = 7  # [m], [m], [kg], [kg m^2], [-], [-], [N/m]

# scene settings (SETTINGS_SIZE,): shared by every body of a run
(
    DT,
    GRAVITY,
    MAX_STEPS,
    UNTIL_REST,
    RESTITUTION_THRESHOLD,
    SLEEP_SPEED,
    SLEEP_TIME,
    PENETRATION_SLOP,
    SOLVER_TOLERANCE,
    SOLVER_ITERATIONS,
    SLEEP,
    QUIET_STEPS,
    THREADS,
) = range(13)
SETTINGS_SIZE = 13  # [s], [m/s^2], [-], [0/1], [m/s], [m/s], [s], [m], [-], [-], [0/1], [0/1], [-]
# UNTIL_REST: the run ends once every body sleeps; SLEEP: islands at rest sleep (colliding scenes; with UNTIL_REST,
# always), the run going on to MAX_STEPS; QUIET_STEPS: a quiet colliding scene takes several grid steps as one
# (``colliding.quiet``); THREADS: numba's thread count for a colliding run's stages on threads, set by the kernel
# for the run once it has bodies to step (``colliding.threads``), 0: numba's count as it is

# per-body statistics (n_bodies, STATS_SIZE) written by every kernel
(FIRST_CONTACT_TIME, N_IMPACTS, N_STEPS, MAX_PENETRATION, REST_TIME, END_TIME, STATUS, FAIL_STEP, N_RECORDED) = range(9)
STATS_SIZE = 9
# FIRST_CONTACT_TIME [s] (nan: never touched), N_IMPACTS, N_STEPS (time steps actually
# integrated), MAX_PENETRATION [m], REST_TIME [s] (nan: never fell asleep), END_TIME [s],
# STATUS (STATUS_OK / STATUS_NONFINITE), FAIL_STEP (grid step at which the state went
# non-finite, -1 if none), N_RECORDED (rows of the trajectory written for this body).
STATUS_OK, STATUS_NONFINITE = 0, 1

# the colliding robust solver's warm start kept between runs (rows, WARM_START_SIZE), ``warm_start_memory``:
# row 0 (contact count, substep length [s], body count k), then per body b < k WARM_BODY_ROWS rows: (its island's
# label while it sleeps, else -1; its sleep timer [s]; 0), its pose at the end of the run (x, y, angle) and its
# PARAM_SIZE parameters three a row, then per contact (key, normal impulse [N s], friction impulse [N s])
WARM_START_SIZE = 3
WARM_BODY_ROWS = 2 + -(-PARAM_SIZE // WARM_START_SIZE)  # rows per body

# impact events (n_bodies, MAX_EVENTS, EVENT_SIZE), recorded only when a trajectory is recorded
EVENT_TIME, EVENT_APPROACH_SPEED, EVENT_CONTACTS = 0, 1, 2  # [s], [m/s], points hit at once
EVENT_SIZE = 3
MAX_EVENTS = 64

# local vertex order (counter-clockwise from the -x,-y corner): b_k = (SIGN_X[k] hx, SIGN_Y[k] hy).
# The robust solver, the rest test and the face numbering use it (adjacent corners bound a face).
SIGN_X = (-1.0, 1.0, 1.0, -1.0)
SIGN_Y = (-1.0, -1.0, 1.0, 1.0)

# the seed demo's vertex order, (-L/2, -W/2), (-L/2, +W/2), (+L/2, +W/2), (+L/2, -W/2): the seed scheme
# resolves corners one after another, so the order changes its results and must be the demo's
SEED_SIGN_X = (-1.0, -1.0, 1.0, 1.0)
SEED_SIGN_Y = (-1.0, 1.0, 1.0, -1.0)
