"""Gymnasium's vector conventions on the native batched env: the three autoreset modes (same-step natively,
next-step and disabled through wrappers) give what Gymnasium's SyncVectorEnv of single envs gives in that
mode, ``render()`` returns a frame per env, and Gymnasium's vector ``RecordVideo`` records the landings."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import box_toss_env  # noqa: F401  (registers BoxToss-v0)
from box_toss_env.wrappers.disabled_autoreset import DisabledAutoreset
from box_toss_env.wrappers.next_step import NextStepAutoreset

N = 4
KWARGS = {"target_face": "mixed"}


def native(**kwargs):
    return gym.make_vec("BoxToss-v0", num_envs=N, vectorization_mode="vector_entry_point", **KWARGS, **kwargs)


def sync(mode):
    return gym.make_vec(
        "BoxToss-v0", num_envs=N, vectorization_mode="sync", vector_kwargs={"autoreset_mode": mode}, **KWARGS
    )


def test_same_step_matches_a_sync_vector_env_in_same_step_mode():
    a, b = native(), sync(AutoresetMode.SAME_STEP)
    assert a.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    np.testing.assert_array_equal(a.reset(seed=7)[0], b.reset(seed=7)[0])
    rng = np.random.default_rng(1)
    for _ in range(3):
        actions = rng.uniform(-1, 1, (N, 3)).astype(np.float32)
        x, y = a.step(actions), b.step(actions)
        for i, name in enumerate(("obs", "reward", "terminated", "truncated")):
            np.testing.assert_array_equal(x[i], y[i], err_msg=name)
        np.testing.assert_array_equal(x[4]["final_obs"], np.stack(y[4]["final_obs"]))


def test_disabled_matches_a_sync_vector_env_in_disabled_mode():
    a, b = DisabledAutoreset(native()), sync(AutoresetMode.DISABLED)
    assert a.metadata["autoreset_mode"] == b.metadata["autoreset_mode"] == AutoresetMode.DISABLED
    np.testing.assert_array_equal(a.reset(seed=[3, 4, 5, 6])[0], b.reset(seed=[3, 4, 5, 6])[0])
    rng = np.random.default_rng(2)
    for step in range(3):
        actions = rng.uniform(-1, 1, (N, 3)).astype(np.float32)
        x, y = a.step(actions), b.step(actions)
        for i, name in enumerate(("obs", "reward", "terminated", "truncated")):
            np.testing.assert_array_equal(x[i], y[i], err_msg=f"step {step}: {name}")
        for key in ("success", "distance", "face_down"):
            np.testing.assert_array_equal(x[4][key], y[4][key], err_msg=key)
        mask = np.ones(N, dtype=bool)
        if step == 1:  # two envs reset now, the other two after a pause: the same episodes come out
            mask[2:] = False
            np.testing.assert_array_equal(
                a.reset(options={"reset_mask": mask})[0][:2], b.reset(options={"reset_mask": mask})[0][:2]
            )
            with pytest.raises(RuntimeError, match=r"envs \[2, 3\] ended and were not reset"):
                a.step(actions)
            mask = ~mask
        np.testing.assert_array_equal(
            a.reset(options={"reset_mask": mask})[0][mask], b.reset(options={"reset_mask": mask})[0][mask]
        )


def test_disabled_refuses_what_it_cannot_do_with_a_clear_error():
    env = DisabledAutoreset(native())
    env.reset(seed=0)
    env.step(env.action_space.sample())
    with pytest.raises(ValueError, match=r"reset_mask.*bool array of shape \(4,\)"):
        env.reset(options={"reset_mask": [True] * N})
    with pytest.raises(ValueError, match="seed must be None"):
        env.reset(seed=1, options={"reset_mask": np.ones(N, dtype=bool)})
    env.reset(options={"reset_mask": np.ones(N, dtype=bool)})
    with pytest.raises(ValueError, match="has not ended"):
        env.reset(options={"reset_mask": np.ones(N, dtype=bool)})
    with pytest.raises(ValueError, match="SAME_STEP"):
        DisabledAutoreset(sync(AutoresetMode.DISABLED))


def test_render_returns_one_frame_per_env_showing_that_env():
    envs = native(render_mode="rgb_array")
    envs.reset(seed=[1, 2, 3, 4])
    frames = envs.render()
    assert len(frames) == N and all(f.shape == frames[0].shape and f.dtype == np.uint8 for f in frames)
    assert frames[0].shape[2] == 3 and not np.array_equal(frames[0], frames[1])  # other targets, other pictures
    single = gym.make("BoxToss-v0", render_mode="rgb_array", **KWARGS)
    single.reset(seed=2)
    picture = np.r_[0:18, 33 : frames[1].shape[0]]  # all but the label's second line ("env 1" / "in the hand")
    np.testing.assert_array_equal(single.render()[picture], frames[1][picture])


def test_record_video_on_the_vector_env_records_each_landing(tmp_path):
    pytest.importorskip("moviepy")  # Gymnasium's RecordVideo writes with moviepy
    import imageio.v3 as iio

    envs = gym.wrappers.vector.RecordVideo(
        NextStepAutoreset(native(render_mode="rgb_array")), str(tmp_path), episode_trigger=lambda episode: True
    )
    envs.reset(seed=0)
    for _ in range(4):  # two throws, each with its reset step
        envs.step(envs.action_space.sample())
    envs.close()
    videos = sorted(tmp_path.glob("*.mp4"))
    assert len(videos) >= 2
    frames = iio.imread(videos[0])
    assert len(frames) == 2 and not np.array_equal(frames[0], frames[1])  # the start and the landing
