"""Contacts of scenes whose boxes collide (``Scene(boxes_collide=True)``): box against box and box
against the floor, as lists of contact points for the colliding solvers. A scene whose boxes cannot
meet compiles none of this (``kernels``).

Conventions, those of the reference text's two-body impulse: a contact pushes body 1 out of body 2
along the unit normal n (body 2 is -1 for the floor, whose normal is (0, 1)); its point p gives the
lever arms r1 = p - x1 and r2 = p - x2, and its gap is the signed distance along n (negative: the
bodies overlap by that much). The relative velocity at the point is u_rel = u1 - u2 with
u = v + omega x r, so the contact approaches where u_rel . n < 0.

Box against box (``box_box_contacts``), separating axes with clipping, as Box2D's polygon collider:
  1. separating axes: for each face f of box A (outward normal n_f, half extent h_f along it) the
     separation of box B from that face is
         s_f = n_f . (x_B - x_A) - |n_f . u_B| hx_B - |n_f . w_B| hy_B - h_f
     (u_B, w_B: B's axes). The boxes are apart by at least max_f s_f; the same for B's faces. Two
     rectangles overlap exactly when every one of these four axes shows overlap.
  2. reference face: the face with the largest separation, with hysteresis: the box whose face it was in
     the last substep keeps it unless the other's is larger by a small tolerance (a new pair: A's unless
     B's is), so the choice does not flicker (``previous_reference``); n = its normal. Incident face: the
     face of the other box whose normal is most anti-parallel to n.
  3. clipping: the incident face's segment is clipped to the reference face's extent along it; each of
     the (at most two) clipped end points within ``margin`` of the reference face is a contact point,
     body 1 being the incident box and body 2 the reference box. An incident face wholly beside the
     reference face (clipping keeps nothing) gives one contact corner against corner (``corner_contact``).
A contact is found while the gap is within ``margin`` (speculative contacts: the solver lets a gap
close but not pass). Each contact gets a key (the pair, the reference and incident faces, the clipped
end) so the next step can start from its impulse (warm starting).

Box against the floor: every corner within ``margin`` of y = 0.

Broad phase: the pairs whose bounding boxes, grown by the margin, overlap, found by sort and sweep
(``broadphase.candidate_pairs``) and visited in the order an all-pairs loop would visit them.
"""

import math

import numpy as np

from ..compile.compilation import jit_stage
from ..geometry import vertex_offset
from ..tunables import REFERENCE_TOLERANCE, START_OVERLAP

# columns of the contact array (one row per contact point)
(
    NX,
    NY,
    R1X,
    R1Y,
    R2X,
    R2Y,
    GAP,
    NORMAL_MASS,
    TANGENT_MASS,
    IMPULSE,
    FRICTION_IMPULSE,
    APPROACH,
    TARGET,
    RESTITUTION,
    FRICTION,
    STIFFNESS,
    PSEUDO_IMPULSE,
) = range(17)
CONTACT_COLUMNS = 17
# columns of the contact id array: the two bodies (body 2 = FLOOR for the floor) and the warm-start key
BODY1, BODY2, KEY = 0, 1, 2
ID_COLUMNS = 3
FLOOR = -1
FEATURES = 64  # keys per pair: (reference box, reference face, incident face, clipped end) or a floor corner


@jit_stage
def face_normal(f, cos_a, sin_a):
    """Outward unit normal of face f of a box at angle alpha (faces as ``geometry.face_down``: 0 = -y,
    1 = +x, 2 = +y, 3 = -x in the body frame); face f runs from corner f to corner f + 1."""
    if f == 0:
        return sin_a, -cos_a
    if f == 1:
        return cos_a, sin_a
    if f == 2:
        return -sin_a, cos_a
    return -cos_a, -sin_a


@jit_stage
def deepest_face(dx, dy, cos_a, sin_a, hx_a, hy_a, cos_b, sin_b, hx_b, hy_b):
    """The face f of box A with the largest separation s_f of box B from it (d = x_B - x_A), and s_f."""
    best = -math.inf
    face = 0
    for f in range(4):
        nx, ny = face_normal(f, cos_a, sin_a)
        half = hy_a if f % 2 == 0 else hx_a
        s = nx * dx + ny * dy - abs(nx * cos_b + ny * sin_b) * hx_b - abs(-nx * sin_b + ny * cos_b) * hy_b - half
        if s > best:
            best = s
            face = f
    return face, best


@jit_stage
def separation(i, j, pose, trig, half):
    """How far boxes i and j are apart at least: the larger of the two boxes' largest face separations (step 1
    above; negative: they overlap, as deep as the least overlap of the four axes)."""
    dx = pose[j, 0] - pose[i, 0]
    dy = pose[j, 1] - pose[i, 1]
    _, sep_i = deepest_face(
        dx, dy, trig[i, 0], trig[i, 1], half[i, 0], half[i, 1], trig[j, 0], trig[j, 1], half[j, 0], half[j, 1]
    )
    _, sep_j = deepest_face(
        -dx, -dy, trig[j, 0], trig[j, 1], half[j, 0], half[j, 1], trig[i, 0], trig[i, 1], half[i, 0], half[i, 1]
    )
    return max(sep_i, sep_j)


@jit_stage
def add_contact(contacts, ids, count, body1, body2, key, normal, lever1, lever2, gap):
    """Append one contact point of body1 against body2 (normal n, lever arms r1, r2 from the bodies' centres to the
    point, gap); returns the new count, or -1 if the arrays are full (they are sized so that they never are)."""
    if count < 0 or count >= contacts.shape[0]:
        return -1
    contacts[count, NX], contacts[count, NY] = normal
    contacts[count, R1X], contacts[count, R1Y] = lever1
    contacts[count, R2X], contacts[count, R2Y] = lever2
    contacts[count, GAP] = gap
    ids[count, BODY1] = body1
    ids[count, BODY2] = body2
    ids[count, KEY] = key
    return count + 1


@jit_stage(inline="always")
def clipped_end(d, d_other, length, px, py, ox, oy):
    """End p of the incident segment from p to o, moved along it onto the reference face's span 0 <= d <= length
    (d, d_other: the ends' distances along the face from its first corner)."""
    if d < 0.0:
        s = d / (d - d_other)
        return px + s * (ox - px), py + s * (oy - py)
    if d > length:
        s = (d - length) / (d - d_other)
        return px + s * (ox - px), py + s * (oy - py)
    return px, py


@jit_stage
def clipped_contacts(ref, inc, face, reference_b, pose, trig, half, margin, code, contacts, ids, count):
    """Contact points of box ``inc`` against face ``face`` of box ``ref`` (step 2 and 3 above)."""
    cr, sr = trig[ref, 0], trig[ref, 1]
    ci, si = trig[inc, 0], trig[inc, 1]
    nx, ny = face_normal(face, cr, sr)
    # incident face: the most anti-parallel
    incident = 0
    lowest = math.inf
    for g in range(4):
        gx, gy = face_normal(g, ci, si)
        d = gx * nx + gy * ny
        if d < lowest:
            lowest = d
            incident = g
    ox, oy = vertex_offset(face, cr, sr, half[ref, 0], half[ref, 1])
    ax, ay = pose[ref, 0] + ox, pose[ref, 1] + oy  # reference face from a to b
    ox, oy = vertex_offset((face + 1) % 4, cr, sr, half[ref, 0], half[ref, 1])
    bx, by = pose[ref, 0] + ox, pose[ref, 1] + oy
    length = math.sqrt((bx - ax) ** 2 + (by - ay) ** 2)
    tx, ty = (bx - ax) / length, (by - ay) / length
    ox, oy = vertex_offset(incident, ci, si, half[inc, 0], half[inc, 1])
    p1x, p1y = pose[inc, 0] + ox, pose[inc, 1] + oy
    ox, oy = vertex_offset((incident + 1) % 4, ci, si, half[inc, 0], half[inc, 1])
    p2x, p2y = pose[inc, 0] + ox, pose[inc, 1] + oy
    d1 = tx * (p1x - ax) + ty * (p1y - ay)
    d2 = tx * (p2x - ax) + ty * (p2y - ay)
    base = code * FEATURES + ((reference_b * 4 + face) * 4 + incident) * 2
    # clip the segment p1 p2 to 0 <= d <= length; beside the face altogether: corner against corner
    if (d1 < 0.0 and d2 < 0.0) or (d1 > length and d2 > length):
        cx, cy = (ax, ay) if d1 < 0.0 else (bx, by)
        end = 0 if (d1 > d2) == (d1 < 0.0) else 1  # the incident end nearer the face's span
        return corner_contact(inc, ref, (cx, cy), (p1x, p1y, p2x, p2y), pose, margin, base + end, contacts, ids, count)
    q1x, q1y = clipped_end(d1, d2, length, p1x, p1y, p2x, p2y)
    q2x, q2y = clipped_end(d2, d1, length, p2x, p2y, p1x, p1y)
    for end in range(2):
        qx, qy = (q1x, q1y) if end == 0 else (q2x, q2y)
        gap = nx * (qx - ax) + ny * (qy - ay)
        if gap <= margin:
            count = add_contact(
                contacts,
                ids,
                count,
                inc,
                ref,
                base + end,
                (nx, ny),
                (qx - pose[inc, 0], qy - pose[inc, 1]),
                (qx - pose[ref, 0], qy - pose[ref, 1]),
                gap,
            )
    return count


@jit_stage
def corner_contact(inc, ref, corner, segment, pose, margin, key, contacts, ids, count):
    """The contact of an incident face that lies wholly beside the reference face (past one of its ends: clipping keeps
    nothing): between the reference face's corner c there and the point q of the incident segment nearest to it,
    along n = (q - c) / |q - c|, gap |q - c|, if within ``margin`` (Box2D's vertex-vertex contact). Without it a
    corner passing just beside another box's corner had no contact and went 1.6 mm into it within one substep
    (the dropped pile of 1,000, seed 1, two corners 0.8 mm apart across and 1.05 mm along the face)."""
    cx, cy = corner
    p1x, p1y, p2x, p2y = segment
    ex, ey = p2x - p1x, p2y - p1y
    s = min(max(((cx - p1x) * ex + (cy - p1y) * ey) / (ex * ex + ey * ey), 0.0), 1.0)
    qx, qy = p1x + s * ex, p1y + s * ey
    gap = math.sqrt((qx - cx) ** 2 + (qy - cy) ** 2)
    if gap > margin or gap == 0.0:
        return count
    return add_contact(
        contacts,
        ids,
        count,
        inc,
        ref,
        key,
        ((qx - cx) / gap, (qy - cy) / gap),
        (qx - pose[inc, 0], qy - pose[inc, 1]),
        (qx - pose[ref, 0], qy - pose[ref, 1]),
        gap,
    )


@jit_stage
def box_box_contacts(i, j, pose, trig, half, margin, code, contacts, ids, count, previous):
    """Contact points of boxes i and j (i < j) within ``margin`` (steps 1 to 3 above); returns the count.
    ``previous``: the last substep's contact keys (increasing) and their count, for the reference's hysteresis."""
    dx = pose[j, 0] - pose[i, 0]
    dy = pose[j, 1] - pose[i, 1]
    face_i, sep_i = deepest_face(
        dx, dy, trig[i, 0], trig[i, 1], half[i, 0], half[i, 1], trig[j, 0], trig[j, 1], half[j, 0], half[j, 1]
    )
    if sep_i > margin:
        return count
    face_j, sep_j = deepest_face(
        -dx, -dy, trig[j, 0], trig[j, 1], half[j, 0], half[j, 1], trig[i, 0], trig[i, 1], half[i, 0], half[i, 1]
    )
    if sep_j > margin:
        return count
    tolerance = REFERENCE_TOLERANCE * min(min(half[i, 0], half[i, 1]), min(half[j, 0], half[j, 1]))
    if previous_reference(previous, code) == 1:  # j's face held: it stays until i's beats it
        use_j = sep_i <= sep_j + tolerance
    else:
        use_j = sep_j > sep_i + tolerance
    if use_j:
        return clipped_contacts(j, i, face_j, 1, pose, trig, half, margin, code, contacts, ids, count)
    return clipped_contacts(i, j, face_i, 0, pose, trig, half, margin, code, contacts, ids, count)


@jit_stage(inline="always")
def first_key_at_least(keys, n, key):
    """The first position among the increasing ``keys[:n]`` whose key is ``key`` or more (n if none): binary search."""
    low, high = 0, n
    while low < high:
        middle = (low + high) // 2
        if keys[middle] < key:
            low = middle + 1
        else:
            high = middle
    return low


@jit_stage(inline="always")
def previous_reference(previous, code):
    """Which box of pair ``code`` gave the reference face of its contacts in the last substep (0: the first, 1: the
    second; the key's bit, ``clipped_contacts``), found by binary search in ``previous`` (keys increasing, their
    count); -1 if the pair kept no contact."""
    keys, n_keys = previous
    first = code * FEATURES
    low = first_key_at_least(keys, n_keys, first)
    if low < n_keys and keys[low] < first + FEATURES:
        return (keys[low] - first) // (FEATURES // 2)
    return -1


@jit_stage
def floor_contacts(i, pose, trig, half, margin, code, contacts, ids, count):
    """Corners of box i within ``margin`` of the floor y = 0."""
    for k in range(4):
        rx, ry = vertex_offset(k, trig[i, 0], trig[i, 1], half[i, 0], half[i, 1])
        gap = pose[i, 1] + ry
        if gap <= margin:  # the lever arm of a floor corner is its offset exactly; the floor's is zero
            px, py = pose[i, 0] + rx, pose[i, 1] + ry
            count = add_contact(
                contacts, ids, count, i, FLOOR, code * FEATURES + k, (0.0, 1.0), (rx, ry), (px - px, py - py), gap
            )
    return count


@jit_stage
def find_contacts(bodies, sweep, pair_keys, n_pairs, include, contacts, previous):
    """Every contact of the scene within reach: box i with ``include`` set against the floor within its
    ``sweep.floor_reach``, and the boxes of each of the first ``n_pairs`` pairs of ``pair_keys`` (keys i n + j,
    i < j, increasing, ``broadphase``) within reach_i + reach_j, in the order (box 0 and the floor, box 0 and box
    1, ..., box 1 and the floor, ...), so the keys increase; into ``contacts`` (``state.Contacts``). ``previous``:
    the last substep's keys and their count (the reference faces' hysteresis, ``box_box_contacts``). Returns the
    number of contacts, or -1 if the arrays are too small (they are sized so that they never are)."""
    pose, half = bodies.pose, bodies.half
    trig, reach, floor_reach = sweep.trig, sweep.reach, sweep.floor_reach
    rows, ids = contacts.rows, contacts.ids
    n = pose.shape[0]
    count = 0
    p = 0
    for i in range(n):
        if include[i]:
            count = floor_contacts(i, pose, trig, half, floor_reach[i], i * (n + 1), rows, ids, count)
        while p < n_pairs and pair_keys[p] // n == i:
            j = pair_keys[p] - i * n
            code = i * (n + 1) + j + 1
            count = box_box_contacts(i, j, pose, trig, half, reach[i] + reach[j], code, rows, ids, count, previous)
            p += 1
        if count < 0:
            return -1
    return count


@jit_stage
def update_geometry(pose, half, awake, trig, bound):
    """cos and sin of every awake box's angle, and the half size of its bounding box (a sleeping box keeps
    those of when it fell asleep: it has not moved since)."""
    for i in range(pose.shape[0]):
        if awake[i]:
            box_geometry(i, pose, half, trig, bound)


@jit_stage(inline="always")
def box_geometry(i, pose, half, trig, bound):
    """cos and sin of box i's angle, and the half size of its bounding box (``update_geometry``)."""
    c = math.cos(pose[i, 2])
    s = math.sin(pose[i, 2])
    trig[i, 0] = c
    trig[i, 1] = s
    bound[i, 0] = abs(c) * half[i, 0] + abs(s) * half[i, 1]
    bound[i, 1] = abs(s) * half[i, 0] + abs(c) * half[i, 1]


def overlapping_boxes(boxes, share: float = START_OVERLAP) -> tuple[int, int, float] | None:
    """The first pair of boxes (i, j, depth) that overlap by more than ``share`` of the smaller half extent
    of the two (separating axes, in plain numpy: used to validate a scene before any kernel runs), or None.
    A little overlap is allowed so that a scene can start from a simulated state (a settled pile overlaps
    by a few 1e-4 of a box's size: the penalty's job)."""
    n = len(boxes)
    if n < 2:
        return None
    centre = np.array([b.position for b in boxes], dtype=float)
    angle = np.array([b.angle for b in boxes], dtype=float)
    half = 0.5 * np.array([(b.length, b.width) for b in boxes], dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    bound = np.stack(
        [np.abs(c) * half[:, 0] + np.abs(s) * half[:, 1], np.abs(s) * half[:, 0] + np.abs(c) * half[:, 1]], axis=1
    )
    for i in range(n - 1):
        near = np.flatnonzero(np.all(np.abs(centre[i + 1 :] - centre[i]) < bound[i + 1 :] + bound[i], axis=1)) + i + 1
        for j in near:
            tolerance = share * min(half[i].min(), half[j].min())
            separation = -math.inf
            for a, b, sign in ((i, j, 1.0), (j, i, -1.0)):
                d = sign * (centre[j] - centre[i])
                for nx, ny, h in ((c[a], s[a], half[a, 0]), (-s[a], c[a], half[a, 1])):
                    reach = abs(nx * c[b] + ny * s[b]) * half[b, 0] + abs(-nx * s[b] + ny * c[b]) * half[b, 1]
                    separation = max(separation, abs(nx * d[0] + ny * d[1]) - reach - h)
            if separation < -tolerance:
                return i, int(j), -separation
    return None
