"""Every threshold and limit of the engine, once, with its unit and what changing it does.

The scene's own settings (``Scene``: dt, restitution threshold, sleep speed and time, slop, the Gauss-Seidel
stop) are a user's to choose and live in the scene; these are the engine's, fixed at compile time (each is a
constant numba folds into the kernels, so changing one recompiles them). Units: [m], [s], [rad], [-] for a
ratio; "[m per m of size + 1 m]" is a length tolerance that scales with the boxes: t (1 + R), R the box's (or the
scene's largest) corner radius. Grouped by the stage that reads them, in the order of the step script
(``stages``).
"""

# -- contacts: when two surfaces touch ---------------------------------------------------------------------------
CONTACT_TOLERANCE = 1e-12
"""[m per m of size + 1 m] a corner this close to a surface touches it, and penetration shallower than this is
never corrected. Larger: contacts and corrections start earlier (a rounding-sized gap counts as touching); smaller
than the rounding of the coordinates it has no effect."""

SIMULTANEOUS_TOLERANCE = 1e-9
"""[m per m of corner radius + 1 m] two corners of a flying box this close in height hit the floor at the same
instant (one impact on both). Larger: nearly level landings are resolved as flat ones (symmetric, no spin
picked up from rounding); smaller: the first corner hits alone and the box rocks."""

REFERENCE_TOLERANCE = 2e-3
"""[share of the smaller box's smaller half extent] in box-box contact, the reference face changes box only if the
other box's face is more separated by this much than the face of the box that held it in the last substep (a new
pair: box A's unless B's is), so the choice does not flicker between substeps. Larger: a stickier choice (contacts
may sit on the less separated face); 0: it follows rounding, and warm starts are lost when it flips. Without the
last substep's choice (1e-3 of the smaller half extent, B only when it beat A), the nearly parallel faces of
staggered thin plates (0.5 x 0.01 m) flipped within 5 um: a column of 10 lost its warm start at every substep,
never slept and sank 2 cm/s into the penalty (thin 100, 8 piles: 0-20 of 100 awake after 6 s; now none)."""

START_OVERLAP = 0.01
"""[share of the thinner box's smaller half extent] how far two boxes of a colliding scene may overlap when it is
built (a settled pile saved from a run overlaps by about 1e-4 of a box); deeper starts are a ValueError."""

FLAT_TOLERANCE = 1e-3
"""[rad] a face this close to level counts as lying on the floor (the rest test of sleeping and of bodies placed
at rest). Larger: boxes tilted on a neighbour may sleep on the floor test; smaller: a box settled to rounding may
never count as lying flat."""

TOUCH_TOLERANCE = 1e-3
"""[share of hx + hy] a corner this close to y = 0 touches the floor in the rest test."""

# -- substeps: no tunnelling -------------------------------------------------------------------------------------
TUNNEL_FRACTION = 0.5
"""[share of the scene's smallest half extent] the most any point of a colliding box moves in one substep relative
to what it can touch in the grid step (the floor, a box within reach: ``colliding.substeps.contact_speeds``).
Smaller: more substeps for fast boxes (cost grows as 1 / this); larger than 1: a thin box can pass through another
within a substep."""

MAX_ROTATION_PER_STEP = 0.05
"""[rad] the most a box turns in one substep (both solvers; the floor-only contact step splits at it). Smaller:
more substeps for spinning boxes, contacts of a turning box tracked more closely."""

MAX_SUBSTEPS = 256
"""[-] substeps of one grid step of the colliding solver at most: the no-tunnelling bound holds up to a relative
speed of MAX_SUBSTEPS TUNNEL_FRACTION min(hx, hy) / dt (1,600 m/s for boxes 10 cm thick at dt = 1/256 s); beyond it
only the speculative contacts stop boxes."""

QUIET_STRIDE = 4
"""[-] grid steps a quiet scene takes as one step (``colliding.quiet``): every awake body slower than the scene's
``sleep_speed`` at every point and one substep of the longer step within the no-tunnelling bound. 1: every grid step
is a step. Larger: a resting scene kept awake costs less (the pile of 16 at 4: 13 instead of 51 us per body per
simulated second, as still; at 8 it jittered, 5e-9 m/s), and runs in chunks are the run at once, bit for bit, only in
chunks of a multiple of it."""

QUIET_MASS_RATIO = 100.0
"""[-] quiet steps only in scenes whose heaviest box is at most this many times the lightest: past it the exact
solves' alternation (its stop: 1e-9 of the impulses' sum) left light boxes under a 1000 times heavier one (stacks
of 5, 6 and 8) slipping 1e-7 to 4e-7 m/s at every quiet step, where at dt they lie still; at 100:1 they lie still
at both. Larger: heavier-on-lighter scenes step quietly too."""

MAX_ROTATION_SUBSTEPS = 64
"""[-] substeps of one contact step of the floor-only solver at most (a box spinning faster than
MAX_ROTATION_SUBSTEPS MAX_ROTATION_PER_STEP / dt turns further per substep)."""

MAX_LOCATED_IMPACTS = 16
"""[-] impacts located in time inside one contact step of the floor-only solver at most; later ones in the step
are resolved on the grid (a box chattering on a corner)."""

MAX_ADVANCE_ITERATIONS = 100_000
"""[-] conservative-advancement steps of a flight to the floor at most; a grazing approach past this is handed to
stepping (never reached in the tests)."""

NEAR_ITERATIONS = 1_000
"""[-] conservative-advancement steps of ``broadphase.time_apart`` (a flying box far from the others) at most; fewer
ends the flight's jump earlier and steps the rest."""

# -- broadphase --------------------------------------------------------------------------------------------------
PAIR_MARGIN = 0.1
"""[share of the scene's smallest half extent] the step's pair search pads each body's reach by this and keeps what it
found while every awake body stays within its padded box (``groups.step_pairs``): a resting pile searches once, not
at every step. Larger: fewer searches, more kept pairs to test (the same pairs either way)."""

ROUNDING = 1e-9
"""[m per m of coordinate + 1 m] the sort-and-sweep intervals are padded by this before the exact overlap test, so
no pair the exact test keeps is missed to rounding. Larger: more pairs tested exactly (slower, same result)."""

SMALL_SORT = 16
"""[-] up to this many pair keys are sorted by insertion, more by heapsort (same order; a speed switch)."""

MIN_CAPACITY = 16
"""[-] contact rows and pair keys a colliding kernel starts with at least (8 contacts and 4 pairs a body, at least
this); the arrays double where a step needs more. Memory only: results do not depend on it."""

# -- solve: the contact impulses ---------------------------------------------------------------------------------
JOINT_LIMIT = 8
"""[contacts] up to this many (with friction), normal and friction impulses are solved exactly together (the Coulomb
contact LCP, ``joint_contact_solve``). Larger: more groups solved exactly, at a cost growing as its cube."""

JOINT_ROUNDS = 24
"""[-] contact state changes of the joint solve at most before it hands the contacts to the alternation."""

DIRECT_LIMIT = 64
"""[contacts] up to this many, the normal impulses are solved exactly (a dense active-set LCP, ``normal_lcp``),
alternating with friction sweeps; more go to projected Gauss-Seidel. Larger: stacks of more boxes carry any mass
ratio, at a cost growing as the cube of the contacts."""

EXACT_MASS_RATIO = 4.0
"""[-] the exact normal solve (up to DIRECT_LIMIT contacts) runs only where a box-box contact of the substep joins
two boxes whose masses differ by more than this factor (``solve.exact_pays``): there Gauss-Seidel carries a heavy
box's load through a light one slowly (a 1 kg box under 100 kg sank); among boxes of like masses its sweeps,
warm-started or from the resting loads' guess, hold a column as the exact solve does, at a fraction of its cost (the
exact solve's pivots on 64 contacts made a dropped pile of 16 cost 900 times Box2D v3). Larger: more scenes on the
sweeps; 1: every small contact set on the exact solve."""

VELOCITY_ITERATIONS = 64
"""[-] rounds of exact normal solve and friction sweep at most per substep (``solve.solve_velocities``)."""

EXACT_CONVERGED = 1e-9
"""[share of the impulses' sum] the exact tiers' alternation (and the restitution polish) stops once a round changes
the impulses by less than this. Also the most exact ``Scene.solver_tolerance`` at which the exact tiers run at all
(a looser tolerance hands their contacts to the sweeps)."""

WARM_START_RESIDUAL = 1e-11
"""[share of the impulses' sum] a set of contacts small enough for the exact solves (at most DIRECT_LIMIT) skips
them where its warm-started impulses already solve it: a Gauss-Seidel step from there would change the impulses by
less than this share of their sum (``solve.warm_start_holds``). A 1000:1 stack kept awake then cost 0.97 times
Box2D v3's, 1.7 times before (``benchmarks.engine_scale``). Larger: the skipped solves' small errors add up (at 1e-9
a row of boxes struck by another lost 1.3e-9 of its momentum, at 1e-11 1e-12); at 1e-12 the exact solves' own
results miss it and it never skips."""

REGULARISATION = 1e-12
"""[share of the diagonal] added to the diagonal of the exact solves' systems, for redundant contacts (a box flat on
the floor: two corners, one slip). Larger: redundant contacts share their load less exactly; 0: singular systems
fall back to the sweeps."""

LCP_TOLERANCE = 1e-12
"""[share of the largest free velocity] how far a contact left free may approach its target (rounding) in the exact
solves, floor corners and box contacts alike. Larger: the active sets settle sooner and contacts sink by that
speed."""

FRICTION_CONE_ROUNDING = 1e-12
"""[share of mu p] a sticking friction may exceed the Coulomb bound by this (rounding) before the joint solve slides
it."""

SINGLE_CHANGE = 100.0
"""[-] Gauss-Seidel sweeps also stop only once no impulse changes by more than this many times the tolerance's share
of the mean impulse (the sum alone let a sweep stop with a few contacts of thousands far from solved)."""

SUPPORT_SLOPE = 0.5
"""[-] |n_y| above which a contact carries weight in a cold start's guess of a resting pile's loads
(``warm_start.resting_loads``)."""

LEVER_SPREAD = 1e-9
"""[m] supports of one body closer together along x than this share its load equally in that guess."""

PAIR_CONDITION = 1e-9
"""[-] two floor corners whose Delassus rows give det(K) below this fraction of K_ii K_jj are parallel (the active
set skips the pair; one of its corners holds)."""

CORNER_SWEEPS = 64
"""[-] Gauss-Seidel sweeps of the floor corners' fallback, for rows parallel to rounding."""

CORNER_CONVERGED = 1e-12
"""[share of the normal impulse] the floor corners' friction sweeps stop once a sweep changes the impulses by less
than this."""

FRICTION_ITERATIONS = 8
"""[-] sweeps over friction and the normal block of a box's floor corners at most (they rarely need two)."""

RESTITUTION_ITERATIONS = 16
"""[-] sweeps of the colliding restitution polish at most."""

HOLD_ROUNDS = 64
"""[-] rounds at most over the contacts the restitution polish left approaching faster than its targets
(``restitution.hold_targets``), each stepping only those. Fewer: a contact the sweeps left short may still close its
gap by up to its shortfall times the substep."""

# -- relax: the penalty ------------------------------------------------------------------------------------------
PENALTY_TRIGGER = 2.0
"""[slops] the penalty starts once a contact is this many ``Scene.penetration_slop`` deep, then removes what lies
beyond one slop (a band, as Box2D 2.x's position solver stops within 3 slops: a pile whose looser solve lets
corners creep to the slop would otherwise run the penalty at every step)."""

PENALTY_FLOOR = 1e-8
"""[m per m of size + 1 m] the penalty never starts on a penetration shallower than this, whatever the slop: rounding (a
pyramid built at rest, kept awake, sinks by 1e-12 m and ran the relax stage at every substep, half its cost at a slop
of 0). Box2D's ``large_pyramid`` (100 rows, 5,050 unit squares) sinks further, 4e-9 m in its first 2 s and 1.1e-8 m
in a minute: at 1e-9 the penalty started after 0.3 s and then ran its 16 sweeps over the whole pyramid's 29,900
contacts at every step, 40% of the run, without converging; at 1e-8 (1.7e-8 m for unit boxes) it does not start in a
minute. Still far below the engine's goals at rest (0.1 mm at 0.2 m, scaled with the boxes). Smaller: the penalty
chases rounding; larger: boxes may rest that deep in one another."""

PENALTY_DAMPING_RATIO = 1.0
"""[-] zeta of the penalty spring: critically damped. Smaller: corrections overshoot and ring; larger: slower."""

PENALTY_ITERATIONS = 16
"""[-] the penalty's Gauss-Seidel sweeps at most (fewer if the scene's ``solver_iterations`` is)."""

# -- bodies alone and groups: work left out ----------------------------------------------------------------------
ALONE_LIMIT = 8
"""[bodies] while at most this many are awake, whole steps for which no two boxes can meet are looked for and taken
by each body alone against the floor. Larger: the search (pairs of awake bodies) costs more in busy scenes."""

ALONE_LOWEST = 0.5
"""[share of the smaller half extent] a box's centre is taken never to sink below this height (its energy bound of
the alone stage: the potential energy it can still give up)."""

SPLIT_SAVING = 64
"""[body-substeps] a step splits its awake bodies into groups of their own substep counts only if that saves at
least this many; else one count for all (the split's own passes cost)."""

SOLVE_SHARE = 4
"""[-] a body's substep in a pile costs about this many times a pass of a substep's loops over it (how much a split
must save against the passes its extra groups add)."""

# -- the seed scheme ---------------------------------------------------------------------------------------------
TANGENT_NORMALISE_MIN = 1e-4
"""[m/s] the seed scheme normalises the slip direction u_t / |u_t| only above this length (the demo's value: part
of the reference scheme, not to be tuned)."""
