"""The former name of ``box_toss_env.wrappers`` (wrappers and adapters around the vector envs, not the vector env
itself, which is ``box_toss_env.envs.box_toss_vector``). Each of its modules is the same module object as the one of
``box_toss_env.wrappers`` (objects pickled under the old path load), imported only when asked for."""
