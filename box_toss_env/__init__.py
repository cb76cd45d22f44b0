"""BoxToss: throw a 2D rigid box onto a floor and be rewarded for how it lands.

Importing the package registers ``BoxToss-v0`` with Gymnasium; the physics engine lives in
``box_toss_env.physics``.
"""

__version__ = "0.1.0"


def _register_envs() -> None:
    """Register ``BoxToss-v0``, its variants, ``BoxToss-Stack-v0`` and ``BoxToss-HiddenPhysics-v0`` with string entry
    points (nothing is imported until an env is made, so ``import box_toss_env`` does not import pygame or the envs)."""
    import gymnasium

    variants: dict[str, dict[str, object]] = {
        "BoxToss-v0": {},
        "BoxToss-LongSide-v0": {"target_face": "long_side"},
        "BoxToss-ShortEnd-v0": {"target_face": "short_end"},
        "BoxToss-ThisSideUp-v0": {"target_face": "exact"},
        "BoxToss-Mixed-v0": {"target_face": "mixed"},
        "BoxToss-OnBox-v0": {"base_box": True},  # come to rest on a base box drawn per episode
    }
    # each variant observed as an image of its scene (envs.pixels): BoxToss-Pixels-v0, BoxToss-ShortEnd-Pixels-v0, ...
    pixels = {
        env_id.replace("-v0", "-Pixels-v0"): {**kwargs, "observation_mode": "pixels"}
        for env_id, kwargs in variants.items()
    }
    for env_id, kwargs in {**variants, **pixels}.items():
        if env_id in gymnasium.registry:  # importlib.reload: keep the existing registration
            continue
        gymnasium.register(
            id=env_id,
            entry_point="box_toss_env.envs.box_toss:BoxTossEnv",
            vector_entry_point="box_toss_env.envs.box_toss_vector:BoxTossVectorEnv",
            kwargs=kwargs,
        )
    if "BoxToss-Stack-v0" not in gymnasium.registry:  # a sequence of throws building a stack (its own env class)
        gymnasium.register(
            id="BoxToss-Stack-v0",
            entry_point="box_toss_env.envs.stack:BoxTossStackEnv",
            vector_entry_point="box_toss_env.envs.stack_vector:BoxTossStackVectorEnv",
        )

    if "BoxToss-HiddenPhysics-v0" not in gymnasium.registry:  # throws of one box whose physics is not observed
        gymnasium.register(
            id="BoxToss-HiddenPhysics-v0",
            entry_point="box_toss_env.envs.hidden_physics:BoxTossHiddenPhysicsEnv",
            vector_entry_point="box_toss_env.envs.hidden_physics:BoxTossHiddenPhysicsVectorEnv",
        )

    if "BoxToss-Goal-v0" not in gymnasium.registry:
        # gymnasium.make returns the goal env itself, without OrderEnforcing and PassiveEnvChecker (the env orders
        # reset before step itself, and passes every checker): their wrappers do not forward compute_reward, which
        # goal-conditioned tools (SB3's check_env, HER) call on the env they are given
        gymnasium.register(
            id="BoxToss-Goal-v0",
            entry_point="box_toss_env.envs.goal:BoxTossGoalEnv",
            vector_entry_point="box_toss_env.envs.goal_vector:BoxTossGoalVectorEnv",
            order_enforce=False,
            disable_env_checker=True,
        )


_register_envs()
