"""The NEXT_STEP view of the native batched env returns exactly what Gymnasium's SyncVectorEnv of
single BoxToss envs returns (NEXT_STEP autoreset), for the same seeds and actions."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import box_toss_env  # noqa: F401  (registers BoxToss-v0)
from box_toss_env.wrappers.next_step import NextStepAutoreset

N = 5
KWARGS = {"target_face": "mixed", "friction_range": (0.2, 0.8)}


def test_matches_a_sync_vector_env_of_single_envs_step_for_step():
    native = NextStepAutoreset(
        gym.make_vec("BoxToss-v0", num_envs=N, vectorization_mode="vector_entry_point", **KWARGS)
    )
    sync = gym.make_vec("BoxToss-v0", num_envs=N, vectorization_mode="sync", **KWARGS)
    assert native.metadata["autoreset_mode"] == sync.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    obs_native, _ = native.reset(seed=3)
    obs_sync, _ = sync.reset(seed=3)
    np.testing.assert_array_equal(obs_native, obs_sync)
    rng = np.random.default_rng(0)
    for step in range(6):  # three throws, each followed by its reset step
        actions = rng.uniform(-1, 1, (N, 3)).astype(np.float32)
        a, b = native.step(actions), sync.step(actions)
        for name, x, y in zip(("obs", "reward", "terminated", "truncated"), a[:4], b[:4], strict=True):
            np.testing.assert_array_equal(x, y, err_msg=f"step {step}: {name}")
        assert a[2].all() == (step % 2 == 0) and not a[3].any()
        if step % 2 == 0:  # the landing's info, as the single envs report it
            for key in ("success", "distance", "final_x", "face_down"):
                np.testing.assert_array_equal(a[4][key], b[4][key], err_msg=key)
        else:  # the new episodes' info
            np.testing.assert_array_equal(a[4]["target_x"], b[4]["target_x"])


def test_refuses_an_env_that_does_not_reset_in_the_same_step():
    with pytest.raises(ValueError, match="SAME_STEP"):
        NextStepAutoreset(gym.make_vec("BoxToss-v0", num_envs=2, vectorization_mode="sync"))
