"""The robust solver for boxes that collide, a module a stage: the step script (``step``), pairs
(``broadphase``), contacts (``narrowphase``), ``prepare``, the penalty (``relax``), ``warm_start``, the
contact solve (``solve``, with the exact Coulomb solve ``joint_contact_solve``, ``normal_lcp`` and ``sweeps``),
``restitution``, bodies alone against the floor (``alone``) and sleeping islands (``islands``); ``limits``
their limits, ``colliding_solver`` every stage's name."""
