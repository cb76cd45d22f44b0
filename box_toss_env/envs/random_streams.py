"""One random stream per env of a batch, as compact as the batch itself.

Each env of the batched BoxToss must draw exactly what a single env seeded the same way draws,
that is the stream of ``gymnasium.utils.seeding.np_random(seed)``: numpy's ``Generator`` on a
``PCG64`` bit generator. A numpy Generator per env costs about 860 bytes and a Python call per
draw; here every env's PCG64 state is one row of 4 uint64 (32 bytes), and one compiled call
draws for the whole batch, bit for bit what numpy's ``Generator.random`` returns.

PCG64 (O'Neill's PCG XSL RR 128/64, as numpy implements it) advances a 128-bit LCG,
    s <- s * M + inc  (mod 2^128),
and outputs rotr64(hi(s) ^ lo(s), hi(s) >> 58); ``random()`` maps an output x to
(x >> 11) * 2^-53 in [0, 1).
"""

from __future__ import annotations

import os

import numpy as np
from gymnasium.utils import seeding

from box_toss_env.physics.compile.background_compile import InterpretedStart
from box_toss_env.physics.compile.compilation import ensure_compiled, jit_kernel, jit_stage

MULTIPLIER_HI = np.uint64(2549297995355413924)  # PCG_DEFAULT_MULTIPLIER_128, high and low 64 bits
MULTIPLIER_LO = np.uint64(4865540595714422341)
LOW_32_BITS = np.uint64(0xFFFFFFFF)
TWO_TO_MINUS_53 = 1.0 / 9007199254740992.0
STATE_HI, STATE_LO, INC_HI, INC_LO = 0, 1, 2, 3
MASK_64 = (1 << 64) - 1


@jit_stage
def multiply_64x64(a, b):
    """The full 128-bit product of two uint64, as (high, low) uint64 halves."""
    a_lo, a_hi = a & LOW_32_BITS, a >> np.uint64(32)
    b_lo, b_hi = b & LOW_32_BITS, b >> np.uint64(32)
    lo_lo = a_lo * b_lo
    hi_lo = a_hi * b_lo
    cross = (lo_lo >> np.uint64(32)) + (hi_lo & LOW_32_BITS) + a_lo * b_hi
    high = a_hi * b_hi + (hi_lo >> np.uint64(32)) + (cross >> np.uint64(32))
    return high, (cross << np.uint64(32)) | (lo_lo & LOW_32_BITS)


@jit_kernel
def fill_uniform(states, out):
    """Fill ``out`` (n, k) with each row's next k doubles in [0, 1), advancing ``states`` (n, 4)."""
    for i in range(out.shape[0]):
        s_hi, s_lo = states[i, STATE_HI], states[i, STATE_LO]
        inc_hi, inc_lo = states[i, INC_HI], states[i, INC_LO]
        for j in range(out.shape[1]):
            # s <- s * M + inc (mod 2^128)
            high, low = multiply_64x64(s_lo, MULTIPLIER_LO)
            high = high + s_hi * MULTIPLIER_LO + s_lo * MULTIPLIER_HI
            s_lo = low + inc_lo
            s_hi = high + inc_hi + (np.uint64(1) if s_lo < low else np.uint64(0))
            # XSL RR output, then 53 bits to a double
            rotation = s_hi >> np.uint64(58)
            folded = s_hi ^ s_lo
            value = (folded >> rotation) | (folded << ((np.uint64(64) - rotation) & np.uint64(63)))
            out[i, j] = np.float64(value >> np.uint64(11)) * TWO_TO_MINUS_53
        states[i, STATE_HI], states[i, STATE_LO] = s_hi, s_lo


def fill_uniform_kernel():
    """``fill_uniform`` (how a background compile rebuilds it: ``background_compile.InterpretedStart``)."""
    return fill_uniform


# -- seeds -----------------------------------------------------------------------------------------
def check_seed(seed, name: str = "seed") -> int | None:
    """``seed`` as a Python int >= 0, or None: any integer type (``np.int64`` too), never a bool; a
    TypeError or ValueError naming ``name`` otherwise. The single and the vector env both use it."""
    if seed is None:
        return None
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)):
        raise TypeError(f"{name} must be None or an integer >= 0, got {type(seed).__name__} {seed!r}")
    if seed < 0:
        raise ValueError(f"{name} must be None or an integer >= 0, got {seed}")
    return int(seed)


def check_seeds(seed, n: int) -> list[int | None] | np.ndarray | None:
    """The seed of each of ``n`` envs (``reset(seed=...)`` of a vector env): None (fresh entropy for
    envs never seeded), an integer s >= 0 (env i gets s + i, as an (n,) uint64 array) or a sequence of
    ``n`` integers >= 0 or Nones (a list or a 1-D numpy array alike). Every seed is checked before any
    is used; an error names the index of the first bad one."""
    expected = f"seed must be None, an int or a list of {n} ints or Nones (ints >= 0)"
    if seed is None:
        return None
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, (bool, np.bool_)):
        if seed < 0:
            raise ValueError(f"{expected}, got {seed}")
        first = int(seed)
        if first + n <= 2**64:
            seeds = np.arange(n, dtype=np.uint64)
            seeds += np.uint64(first)
            return seeds
        return [first + i for i in range(n)]
    if isinstance(seed, np.ndarray):
        if seed.ndim != 1:
            raise ValueError(f"{expected}, got an array of shape {seed.shape}")
    elif not isinstance(seed, (list, tuple)):
        raise TypeError(f"{expected}, got {type(seed).__name__} {seed!r}")
    if len(seed) != n:
        raise ValueError(f"{expected}, got {len(seed)} seeds")
    # all integers (no bool, no None): checked as one array; otherwise one by one
    array = seed if isinstance(seed, np.ndarray) else None
    if array is None and not ({type(value) for value in seed} - {int}):
        array = np.array(seed)
    if array is not None and array.dtype.kind in "iu":
        negative = np.flatnonzero(array < 0)
        if len(negative):
            raise ValueError(f"{expected}: seed[{negative[0]}] is {array[negative[0]]}")
        return array.astype(np.uint64)
    checked: list[int | None] = []
    for i, value in enumerate(seed):
        try:
            checked.append(check_seed(value, f"seed[{i}]"))
        except (TypeError, ValueError) as error:
            raise type(error)(f"{expected}: {error}") from None
    return checked


INIT_A, MULT_A, INIT_B, MULT_B = 0x43B0D7E5, 0x931E8875, 0x8B51F9DD, 0x58F38DED  # numpy's SeedSequence
MIX_MULT_L, MIX_MULT_R, XSHIFT, POOL_SIZE = 0xCA01F9DD, 0x4973F715, 16, 4
MASK_32 = (1 << 32) - 1


def seed_sequence_words(entropy: np.ndarray) -> np.ndarray:
    """The first 4 uint64 of ``np.random.SeedSequence(seed).generate_state(4, np.uint64)`` for each
    row of ``entropy`` (n, k) uint32 (a seed's 32-bit words, least significant first), for all rows at
    once: numpy's SeedSequence, vectorised over seeds (its hash constants do not depend on the data)."""
    n, k = entropy.shape
    constant = [INIT_A]

    def hashmix(value: np.ndarray) -> np.ndarray:
        value = value ^ np.uint32(constant[0])
        constant[0] = (constant[0] * MULT_A) & MASK_32
        value = value * np.uint32(constant[0])
        return value ^ (value >> np.uint32(XSHIFT))

    def mix(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        result = np.uint32(MIX_MULT_L) * x - np.uint32(MIX_MULT_R) * y
        return result ^ (result >> np.uint32(XSHIFT))

    zeros = np.zeros(n, dtype=np.uint32)
    pool = [hashmix(entropy[:, i] if i < k else zeros) for i in range(POOL_SIZE)]
    for source in range(POOL_SIZE):
        for destination in range(POOL_SIZE):
            if source != destination:
                pool[destination] = mix(pool[destination], hashmix(pool[source]))
    for source in range(POOL_SIZE, k):
        for destination in range(POOL_SIZE):
            pool[destination] = mix(pool[destination], hashmix(entropy[:, source]))
    output_constant = INIT_B
    words = []
    for i in range(2 * 4):
        value = pool[i % POOL_SIZE] ^ np.uint32(output_constant)
        output_constant = (output_constant * MULT_B) & MASK_32
        value = value * np.uint32(output_constant)
        words.append((value ^ (value >> np.uint32(XSHIFT))).astype(np.uint64))
    return np.stack([words[2 * i] | (words[2 * i + 1] << np.uint64(32)) for i in range(4)], axis=1)


def multiply_add_128(hi, lo, inc_hi, inc_lo):
    """(hi, lo) * PCG's multiplier + (inc_hi, inc_lo) mod 2^128, on uint64 arrays (``multiply_64x64``'s
    Python source, which works on arrays as it does on scalars)."""
    high, low = getattr(multiply_64x64, "py_func", multiply_64x64)(lo, MULTIPLIER_LO)
    high = high + hi * MULTIPLIER_LO + lo * MULTIPLIER_HI
    new_lo = low + inc_lo
    return high + inc_hi + (new_lo < low).astype(np.uint64), new_lo


def pcg64_states(words: np.ndarray) -> np.ndarray:
    """PCG64 states (n, 4) (state hi, lo, inc hi, lo) seeded as numpy's ``PCG64(seed_sequence)`` is
    from ``generate_state(4, np.uint64)`` = ``words`` (n, 4): PCG's srandom, s = 0, inc = 2 seq + 1,
    step, s += initstate, step."""
    with np.errstate(over="ignore"):
        inc_hi = (words[:, 2] << np.uint64(1)) | (words[:, 3] >> np.uint64(63))
        inc_lo = (words[:, 3] << np.uint64(1)) | np.uint64(1)
        hi, lo = multiply_add_128(np.zeros_like(inc_hi), np.zeros_like(inc_lo), inc_hi, inc_lo)
        lo_sum = lo + words[:, 1]
        hi = hi + words[:, 0] + (lo_sum < lo).astype(np.uint64)
        hi, lo = multiply_add_128(hi, lo_sum, inc_hi, inc_lo)
    return np.stack([hi, lo, inc_hi, inc_lo], axis=1)


SEED_SEQUENCE_WORDS = 4  # entropy words a row holds: a seed's 2 (low, high), fresh entropy's 4


def seed_sequence_constants() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The (xor, multiplier) pairs of SeedSequence's hashes, in the order numpy applies them: 16 for
    mixing the pool (4 to take the entropy in, 12 to mix every word into every other), 8 to draw the 8
    32-bit output words. They do not depend on the data (numpy's ``_seed_sequence`` constants)."""

    def chain(init: int, mult: int, count: int) -> tuple[np.ndarray, np.ndarray]:
        xors, mults, constant = [], [], init
        for _ in range(count):
            xors.append(constant)
            constant = (constant * mult) & MASK_32
            mults.append(constant)
        return np.array(xors, dtype=np.uint64), np.array(mults, dtype=np.uint64)

    return (*chain(INIT_A, MULT_A, POOL_SIZE * POOL_SIZE), *chain(INIT_B, MULT_B, 2 * 4))


POOL_XOR, POOL_MULT, OUTPUT_XOR, OUTPUT_MULT = seed_sequence_constants()
MASK_32_U64 = np.uint64(MASK_32)
SHIFT_32 = np.uint64(32)
XSHIFT_U64 = np.uint64(XSHIFT)


@jit_kernel
def seed_states_kernel(entropy, states):
    """``states`` (n, 4) <- for each row of ``entropy`` (n, m <= 4) uint32 (a seed's 32-bit words, least
    significant first, zeros above its highest), the PCG64 state numpy seeds from
    ``SeedSequence(words)``: ``seed_sequence_words`` then ``pcg64_states``, one row at a time in one
    compiled pass (no temporary arrays). A seed's leading zero words may be kept: with at most 4
    words SeedSequence hashes a missing word as a 0."""
    pool = np.zeros(POOL_SIZE, dtype=np.uint64)
    words = np.zeros(2 * 4, dtype=np.uint64)
    for i in range(entropy.shape[0]):
        for j in range(POOL_SIZE):
            value = np.uint64(entropy[i, j]) if j < entropy.shape[1] else np.uint64(0)
            value = ((value ^ POOL_XOR[j]) * POOL_MULT[j]) & MASK_32_U64
            pool[j] = value ^ (value >> XSHIFT_U64)
        h = POOL_SIZE
        for source in range(POOL_SIZE):
            for destination in range(POOL_SIZE):
                if source != destination:
                    hashed = ((pool[source] ^ POOL_XOR[h]) * POOL_MULT[h]) & MASK_32_U64
                    hashed ^= hashed >> XSHIFT_U64
                    h += 1
                    mixed = (np.uint64(MIX_MULT_L) * pool[destination] - np.uint64(MIX_MULT_R) * hashed) & MASK_32_U64
                    pool[destination] = mixed ^ (mixed >> XSHIFT_U64)
        for j in range(2 * 4):
            value = ((pool[j % POOL_SIZE] ^ OUTPUT_XOR[j]) * OUTPUT_MULT[j]) & MASK_32_U64
            words[j] = value ^ (value >> XSHIFT_U64)
        # PCG64's srandom: s = 0, inc = 2 seq + 1, step, s += initstate, step (as ``pcg64_states``)
        init_hi, init_lo = words[0] | (words[1] << SHIFT_32), words[2] | (words[3] << SHIFT_32)
        seq_hi, seq_lo = words[4] | (words[5] << SHIFT_32), words[6] | (words[7] << SHIFT_32)
        inc_hi = (seq_hi << np.uint64(1)) | (seq_lo >> np.uint64(63))
        inc_lo = (seq_lo << np.uint64(1)) | np.uint64(1)
        hi, lo = inc_hi, inc_lo  # 0 * M + inc
        lo_sum = lo + init_lo
        hi = hi + init_hi + (np.uint64(1) if lo_sum < lo else np.uint64(0))
        high, low = multiply_64x64(lo_sum, MULTIPLIER_LO)
        high = high + hi * MULTIPLIER_LO + lo_sum * MULTIPLIER_HI
        lo = low + inc_lo
        states[i, STATE_HI] = high + inc_hi + (np.uint64(1) if lo < low else np.uint64(0))
        states[i, STATE_LO] = lo
        states[i, INC_HI] = inc_hi
        states[i, INC_LO] = inc_lo


COMPILED_SEEDING_MIN = 4096
"""Batches of at least this many seeds are seeded by ``seed_states_kernel`` (compiled, or loaded from
numba's cache, at its first use); smaller ones by the numpy code, which needs no compilation and takes
a few milliseconds at most. Both give numpy's states bit for bit."""


def states_from_entropy(entropy: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """PCG64 states (n, 4) seeded from ``entropy`` (n, m <= 4) uint32, each row as ``SeedSequence`` of
    its words (least significant first; leading zero words make no difference); written into ``out``
    (a C-contiguous (n, 4) uint64 array) if given."""
    entropy = np.ascontiguousarray(entropy, dtype=np.uint32)
    if len(entropy) < COMPILED_SEEDING_MIN:
        states = pcg64_states(seed_sequence_words(entropy))
        if out is None:
            return states
        out[...] = states
        return out
    states = np.empty((len(entropy), 4), dtype=np.uint64) if out is None else out
    ensure_compiled(seed_states_kernel, (entropy, states))
    seed_states_kernel(entropy, states)
    return states


def seed_words(seeds: np.ndarray) -> np.ndarray:
    """(n, 2) uint32: the low and high 32-bit words of each uint64 seed (a view where possible)."""
    return np.ascontiguousarray(seeds, dtype="<u8").view("<u4").reshape(len(seeds), 2)


def fresh_states(n: int, out: np.ndarray | None = None) -> np.ndarray:
    """PCG64 states (n, 4) from fresh entropy, 128 bits each, as ``SeedSequence(None)`` draws it
    (written into ``out`` if given)."""
    return states_from_entropy(np.frombuffer(os.urandom(16 * n), dtype=np.uint32).reshape(n, 4), out)


def seeded_states(seeds, out: np.ndarray | None = None) -> np.ndarray:
    """PCG64 states (n, 4) of ``seeding.np_random(seed)`` for each seed (a uint64 array, or a list of
    ints >= 0 and Nones for fresh entropy), computed for all seeds at once, bit for bit numpy's; seeds
    of 2^64 and more go through numpy one by one. A uint64 array's states are written into ``out`` if
    given (a C-contiguous (n, 4) uint64 array)."""
    if isinstance(seeds, np.ndarray):
        return states_from_entropy(seed_words(seeds), out)
    states = np.zeros((len(seeds), 4), dtype=np.uint64)
    fresh = [i for i, seed in enumerate(seeds) if seed is None]
    if fresh:
        states[fresh] = fresh_states(len(fresh))
    index = np.array([i for i, seed in enumerate(seeds) if seed is not None and seed < 2**64], dtype=np.int64)
    if len(index):
        states[index] = states_from_entropy(seed_words(np.array([seeds[i] for i in index], dtype=np.uint64)))
    for i, seed in enumerate(seeds):
        if seed is not None and seed >= 2**64:
            states[i] = numpy_state(seed)
    return states


def numpy_state(seed: int | None) -> tuple[int, int, int, int]:
    """The PCG64 state of ``seeding.np_random(seed)``, from numpy itself."""
    generator, _ = seeding.np_random(seed)
    state = generator.bit_generator.state["state"]
    return state["state"] >> 64, state["state"] & MASK_64, state["inc"] >> 64, state["inc"] & MASK_64


class RandomStreams:
    """``n`` independent PCG64 streams, each seeded as ``gymnasium.utils.seeding.np_random``."""

    def __init__(self, n: int):
        self.states = np.zeros((n, 4), dtype=np.uint64)
        self.seeded = np.zeros(n, dtype=bool)
        self._start = InterpretedStart(fill_uniform, ("box_toss_env.envs.random_streams", "fill_uniform_kernel", {}))

    def seed(self, index: int, seed: int | None) -> None:
        """Start stream ``index`` where ``seeding.np_random(seed)`` starts (fresh entropy for None)."""
        self.states[index] = numpy_state(check_seed(seed))
        self.seeded[index] = True

    def seed_all(self, seeds) -> None:
        """Start every stream where ``seeding.np_random`` starts with its seed (``check_seeds``'s
        result: None re-seeds with fresh entropy only the streams never seeded), all at once."""
        if seeds is None:
            if not self.seeded.any():  # the first reset: every stream, written in place
                fresh_states(len(self.states), self.states)
            else:
                unseeded = np.flatnonzero(~self.seeded)
                if len(unseeded):
                    self.states[unseeded] = fresh_states(len(unseeded))
        elif isinstance(seeds, np.ndarray):
            seeded_states(seeds, self.states)
        else:
            keep = np.array([seed is None and self.seeded[i] for i, seed in enumerate(seeds)], dtype=bool)
            new = seeded_states(seeds)
            self.states[~keep] = new[~keep]
        self.seeded[:] = True

    def fill_uniform(self, out: np.ndarray) -> np.ndarray:
        """Row i of ``out`` (n, k) gets stream i's next k uniform doubles; returns ``out``."""
        if not self._start.run((self.states, out), (self.states, out)):
            fill_uniform(self.states, out)
        return out

    def generator(self, index: int) -> np.random.Generator:
        """A numpy Generator at stream ``index``'s current position (a copy: drawing from it does not
        advance the stream)."""
        bit_generator = np.random.PCG64()
        row = [int(v) for v in self.states[index]]
        bit_generator.state = {
            "bit_generator": "PCG64",
            "state": {"state": (row[STATE_HI] << 64) | row[STATE_LO], "inc": (row[INC_HI] << 64) | row[INC_LO]},
            "has_uint32": 0,
            "uinteger": 0,
        }
        return np.random.Generator(bit_generator)
