"""Broadphase of scenes whose boxes collide: which pairs of boxes can touch, by sort and sweep.

Box i covers the axis-aligned box |p - x_i| <= b_i + r_i (b_i: the half size of its bounding box,
r_i: its reach, what it can travel in the substep); two boxes are a candidate pair when these overlap,
the test the all-pairs broadphase made on every pair:

    |x_j - x_i| <= b_i,x + b_j,x + r_i + r_j   and   |y_j - y_i| <= b_i,y + b_j,y + r_i + r_j.

Sort and sweep: along one axis each box is the interval [lo_i, hi_i] = x_i -+ (b_i,x + r_i); with the boxes
sorted by lo, the boxes whose interval overlaps box i's are those after it whose lo is <= hi_i, so a sweep
finds them without looking at any other pair, and each found pair is kept only if the exact test above holds
(the intervals are padded by a rounding margin, so no pair the exact test keeps is missed). The order is
kept from one call to the next and repaired by insertion sort: between substeps the boxes barely move, so
that costs O(n + swaps), and the whole search O(n + pairs found along the axis) instead of n (n - 1) / 2
tests. The sweep runs along the axis on which the boxes are spread further (x for a wide pile, y for a tall
stack), chosen by the caller.

The pairs come back as keys i n + j (i < j) in increasing order, the order the all-pairs loop visited them,
so that what follows (contact points, their warm-start keys, the solver's sweep order) is the same.
"""

import math

from ..compile.compilation import jit_stage
from ..robust.flight import flight_state
from ..tunables import NEAR_ITERATIONS, ROUNDING, SMALL_SORT


@jit_stage
def sweep_axis(pose, include):
    """0 (x) or 1 (y): the axis along which the included boxes' centres are spread further."""
    low_x = low_y = math.inf
    high_x = high_y = -math.inf
    for b in range(pose.shape[0]):
        if include[b]:
            low_x = min(low_x, pose[b, 0])
            high_x = max(high_x, pose[b, 0])
            low_y = min(low_y, pose[b, 1])
            high_y = max(high_y, pose[b, 1])
    return 0 if high_x - low_x >= high_y - low_y else 1


@jit_stage
def insertion_sort(order, keys):
    """Sort ``order`` (indices into ``keys``) by ``keys`` in place; O(n + swaps), so nearly free on an
    order that is almost sorted already."""
    for p in range(1, order.shape[0]):
        item = order[p]
        key = keys[item]
        q = p - 1
        while q >= 0 and keys[order[q]] > key:
            order[q + 1] = order[q]
            q -= 1
        order[q + 1] = item


@jit_stage
def sort_keys(keys, count):
    """Sort ``keys[:count]`` in place without allocating (numba's ``sort`` keeps a stack array, which needs
    reference counting in every stage that calls it): insertion sort up to SMALL_SORT keys, heapsort beyond
    (O(count log count), in place). The keys are distinct, so every sort gives the same order."""
    if count <= SMALL_SORT:
        for p in range(1, count):
            item = keys[p]
            q = p - 1
            while q >= 0 and keys[q] > item:
                keys[q + 1] = keys[q]
                q -= 1
            keys[q + 1] = item
        return
    for start in range(count // 2 - 1, -1, -1):
        sift_down(keys, start, count)
    for end in range(count - 1, 0, -1):
        keys[0], keys[end] = keys[end], keys[0]
        sift_down(keys, 0, end)


@jit_stage(inline="always")
def sift_down(keys, root, end):
    """Heapsort's step: move ``keys[root]`` down the max-heap ``keys[:end]`` to its place."""
    while True:
        child = 2 * root + 1
        if child >= end:
            return
        if child + 1 < end and keys[child + 1] > keys[child]:
            child += 1
        if keys[root] >= keys[child]:
            return
        keys[root], keys[child] = keys[child], keys[root]
        root = child


@jit_stage(inline="always")
def overlaps(dx, dy, bound_x, bound_y, margin):
    """The exact test of the module docstring for two boxes whose centres are (dx, dy) apart, with summed
    half extents (bound_x, bound_y) and summed reaches ``margin``: |dx| <= bound_x + margin and
    |dy| <= bound_y + margin. Scalars only, so that the sweep's inner loop handles no array."""
    return abs(dx) <= bound_x + margin and abs(dy) <= bound_y + margin


@jit_stage(inline="always")
def pair_overlaps(pose, bound, reach, a, b):
    """Whether boxes a and b pass the test of the module docstring (``overlaps``) at their reaches ``reach``."""
    return overlaps(
        pose[b, 0] - pose[a, 0],
        pose[b, 1] - pose[a, 1],
        bound[a, 0] + bound[b, 0],
        bound[a, 1] + bound[b, 1],
        reach[a] + reach[b],
    )


@jit_stage
def sort_intervals(pose, bound, reach, axis, order, low):
    """Each box's interval start along ``axis`` (padded by ROUNDING) into ``low``, and ``order`` (the sweep order of
    the last search, any permutation of the boxes) repaired to increasing starts."""
    for b in range(pose.shape[0]):
        pad = ROUNDING * (1.0 + abs(pose[b, axis]))
        low[b] = pose[b, axis] - bound[b, axis] - reach[b] - pad
    insertion_sort(order, low)


@jit_stage(inline="always")
def interval_end(pose, bound, reach, axis, i):
    """The end of box i's interval along ``axis`` (padded by ROUNDING)."""
    return pose[i, axis] + bound[i, axis] + reach[i] + ROUNDING * (1.0 + abs(pose[i, axis]))


@jit_stage
def candidate_pairs(pose, bound, reach, include, moving, axis, order, low, keys):
    """The candidate pairs (module docstring) among the boxes with ``include`` set, of which at least one
    has ``moving`` set, as keys i n + j (i < j) in increasing order in ``keys``. ``order`` is the sweep order
    of the last call (any permutation of the boxes), repaired in place; ``low`` is work space. Returns the
    number of pairs, or -1 if ``keys`` is too short (the caller grows it and asks again)."""
    n = pose.shape[0]
    sort_intervals(pose, bound, reach, axis, order, low)
    count = 0
    for p in range(n):
        i = order[p]
        if not include[i]:
            continue
        high = interval_end(pose, bound, reach, axis, i)
        for q in range(p + 1, n):
            j = order[q]
            if low[j] > high:
                break
            if not include[j] or not (moving[i] or moving[j]):
                continue
            a, b = min(i, j), max(i, j)
            if pair_overlaps(pose, bound, reach, a, b):
                if count >= keys.shape[0]:
                    return -1
                keys[count] = a * n + b
                count += 1
    sort_keys(keys, count)
    return count


@jit_stage
def substep_pairs(pose, sweep, n_pairs, include):
    """A substep's candidate pairs: of the step's (``sweep.pairs[:n_pairs]``, found at every body's reach over the
    whole step, ``groups.step_pairs``), those whose two boxes have ``include`` set and pass the exact test of the
    module docstring with the substep's bounds and reaches (``sweep.bound``, ``sweep.reach``), into
    ``sweep.substep_pairs`` in the same increasing order (``kept_pairs``); returns how many. These are the pairs a
    search at the substep's reach finds (``candidate_pairs``), since the step's reach holds what a body travels in the
    step."""
    return kept_pairs(pose, sweep.bound, sweep.reach, include, sweep.pairs, n_pairs, sweep.substep_pairs)


@jit_stage(inline="always")
def kept_pairs(pose, bound, reach, include, keys, count, out):
    """Of the pairs ``keys[:count]``, those whose two boxes have ``include`` set and pass the exact test of the module
    docstring at ``bound`` and ``reach`` (``pair_overlaps``), into ``out`` in the same order; returns how many, or -1
    if ``out`` is too short."""
    n = pose.shape[0]
    found = 0
    for p in range(count):
        a = keys[p] // n
        b = keys[p] - a * n
        if include[a] and include[b] and pair_overlaps(pose, bound, reach, a, b):
            if found >= out.shape[0]:
                return -1
            out[found] = keys[p]
            found += 1
    return found


@jit_stage
def box_bound(cos_a, sin_a, half_length, half_width):
    """Half size (x, y) of the axis-aligned bounding box of a box at the angle of (cos_a, sin_a)."""
    return (abs(cos_a) * half_length + abs(sin_a) * half_width, abs(sin_a) * half_length + abs(cos_a) * half_width)


@jit_stage
def time_apart(b, pose, vel, half, radius, awake, gravity, horizon, resolution):
    """A time tau in [0, horizon] up to which flying box b stays apart from every other box: their bounding
    boxes do not overlap (conservative advancement on the bounding boxes' gap).

    The gap of two bounding boxes, max(|dx| - (b_x + b'_x), |dy| - (b_y + b'_y)), closes no faster than
    U = |v| + |omega| R + |v'| + |omega'| R' (centres and corners), and U grows by at most |g| per second
    for each of the two that flies (a sleeping box does not move); so it stays open for at least the
    positive root of U t + A t^2 / 2 = gap. Stepping by the smallest of these over the other boxes never
    skips an overlap. Stops, returning the time reached, once a step is shorter than ``resolution`` (the
    caller rounds down to whole time steps) or the gap is closed.
    """
    n = pose.shape[0]
    tau = 0.0
    for _ in range(NEAR_ITERATIONS):
        xb, yb, ab, vxb, vyb, wb = flight_state(
            pose[b, 0], pose[b, 1], pose[b, 2], vel[b, 0], vel[b, 1], vel[b, 2], gravity, tau
        )
        bx, by = box_bound(math.cos(ab), math.sin(ab), half[b, 0], half[b, 1])
        speed_b = math.sqrt(vxb * vxb + vyb * vyb) + abs(wb) * radius[b]
        step = math.inf
        for o in range(n):
            if o == b:
                continue
            xo, yo, ao, speed, accel = pose[o, 0], pose[o, 1], pose[o, 2], speed_b, abs(gravity)
            if awake[o]:
                xo, yo, ao, vxo, vyo, wo = flight_state(
                    pose[o, 0], pose[o, 1], pose[o, 2], vel[o, 0], vel[o, 1], vel[o, 2], gravity, tau
                )
                speed += math.sqrt(vxo * vxo + vyo * vyo) + abs(wo) * radius[o]
                accel += abs(gravity)
            ox, oy = box_bound(math.cos(ao), math.sin(ao), half[o, 0], half[o, 1])
            gap = max(abs(xo - xb) - bx - ox, abs(yo - yb) - by - oy)
            if gap <= 0.0:
                return tau
            root = math.sqrt(speed * speed + 2.0 * accel * gap)
            step = min(step, 2.0 * gap / (speed + root) if speed + root > 0.0 else math.inf)
        if tau + step >= horizon:
            return horizon
        if step < resolution:
            return tau
        tau += step
    return tau
