"""The fixed targets every evaluation throws at: which seeds, how many (light: the commands' help reads it).

Target i is what ``gymnasium.make(env_id).reset(seed=first_seed + i)`` draws (``agents.evaluation``).
"""

TEST_FIRST_SEED, TEST_TARGETS = 10_000, 1_024  # the report's targets
VALIDATION_FIRST_SEED = 20_000  # periodic evaluation during training: other targets than the report's
STACK_TEST_EPISODES = 256  # the report's episodes of a stacking env (seeds 10000...): 4 throws each
