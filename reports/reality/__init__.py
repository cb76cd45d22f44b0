"""Error against reality: our engine, and the engines a user would pick instead, on measured drops of a real
square (DAIRLab/ImpactModeling, BSD-3; docs/reality.md).

    python -m reports.reality.download --out DIR   # the 500 measured drops, checked against square_drops.sha256
    python -m reports.reality --data DIR --write-docs   # docs/reality.md and its figures
    python -m reports.reality.impacts --data DIR --ellipse FILE --write-docs   # its section on the impact alone

Without ``--write-docs`` both write into build/reports/ (ignored by git) instead.

``data`` reads and cleans a folder of the measured files, ``error`` simulates from the measured states and
fits the material, ``synthetic`` writes drops in the same format from our engine (the tests' fixture);
``impact_law`` applies the engine's impact law (and a point-contact Newton + Coulomb map) to one impact at a
time, ``impacts`` scores them on the square's first impacts and on the ellipse impacts of the planar impact
dataset (``data_ellipse.mat``, read where the user put it).
"""
