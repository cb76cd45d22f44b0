"""Reports generated from the engine by one command each (figures are never typed by hand).

- ``python -m reports.precision --write-docs``: error against run time, ``docs/precision.md``;
- ``python -m reports.stability --write-docs``: stiff and extreme cases, ``docs/stability.md``;
- ``python -m reports.collisions --write-docs``: boxes that collide, in our solvers, pymunk and Box2D (who agrees
  with whom), ``docs/collisions.md``;
- ``python -m reports.reality --data DIR --write-docs``: error against measured drops, ``docs/reality.md``.

Without ``--write-docs`` each writes into ``build/reports/`` (ignored by git) or ``--out``, and no tracked file
changes. ``--quick`` runs a reduced version of each (into ``build/reports/``), which the tests in
``tests/reports/`` run so the reports cannot rot. Shared pieces: ``cases`` (scenes, exact answers,
the seeded throws), ``timing`` (warm-up, then the minimum of repeats), ``document`` (tables,
figures, the section of docs/reports.md).
"""
