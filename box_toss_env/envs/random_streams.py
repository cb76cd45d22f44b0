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

import numpy as np
from gymnasium.utils import seeding

from box_toss_env.physics.background_compile import InterpretedStart
from box_toss_env.physics.compilation import jit_kernel, jit_stage

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


class RandomStreams:
    """``n`` independent PCG64 streams, each seeded as ``gymnasium.utils.seeding.np_random``."""

    def __init__(self, n: int):
        self.states = np.zeros((n, 4), dtype=np.uint64)
        self.seeded = np.zeros(n, dtype=bool)
        self._start = InterpretedStart(fill_uniform, ("box_toss_env.envs.random_streams", "fill_uniform_kernel", {}))

    def seed(self, index: int, seed: int | None) -> None:
        """Start stream ``index`` where ``seeding.np_random(seed)`` starts (fresh entropy for None)."""
        generator, _ = seeding.np_random(seed)
        state = generator.bit_generator.state["state"]
        self.states[index] = (state["state"] >> 64, state["state"] & MASK_64, state["inc"] >> 64,
                              state["inc"] & MASK_64)
        self.seeded[index] = True

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
        bit_generator.state = {"bit_generator": "PCG64",
                               "state": {"state": (row[STATE_HI] << 64) | row[STATE_LO],
                                         "inc": (row[INC_HI] << 64) | row[INC_LO]},
                               "has_uint32": 0, "uinteger": 0}
        return np.random.Generator(bit_generator)
