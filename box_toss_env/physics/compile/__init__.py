"""How the engine is compiled, apart from the physics: numba's decorators for stages and kernels, its on-disk
cache and one compilation at a time (``compilation``), and the kernel compiled in a background process while a
first call runs interpreted (``background_compile``)."""
