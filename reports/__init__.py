"""Reports generated from the engine by one command each (figures are never typed by hand).

- ``python -m reports.precision``: error against run time, ``docs/precision.md``;
- ``python -m reports.stability``: stiff and extreme cases, ``docs/stability.md``;
- ``python -m reports.collisions``: boxes that collide, in our solvers, pymunk and Box2D (who agrees with
  whom), ``docs/collisions.md``.

``--quick`` runs a reduced version of each (into ``build/reports/``), which the tests in
``tests/reports/`` run so the reports cannot rot. Shared pieces: ``cases`` (scenes, exact answers,
the seeded throws), ``timing`` (warm-up, then the minimum of repeats), ``document`` (tables,
figures, the section of docs/reports.md).
"""
