"""Episodes of a single env and their bit-identical comparison, shared by the env tests."""

import numpy as np


def rollout(env, seed, actions):
    """(reset obs, reset info, step results) of one episode per action, the first reset seeded."""
    episodes = []
    for k, action in enumerate(actions):
        obs, info = env.reset(seed=seed if k == 0 else None)
        episodes.append((obs, info, env.step(action)))
    return episodes


def assert_identical(a, b):
    """Bit-identical nested episodes (arrays, floats, dicts)."""
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            assert_identical(a[key], b[key])
    elif isinstance(a, (tuple, list)):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            assert_identical(x, y)
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes()
    else:
        assert type(a) is type(b) and (a == b or (a != a and b != b)), (a, b)
