"""The robust solver for boxes that collide, a module a stage: the kernel and its grid steps (``kernel``), the
step script (``step``), the step state (``state``), the substep count and reach (``substeps``), pairs
(``broadphase``), contacts (``narrowphase``), ``prepare``, the penalty (``relax``), ``warm_start``, the contact solve
(``solve``, with the exact Coulomb solve ``joint_contact_solve``, ``normal_lcp`` and ``sweeps``), ``restitution``,
groups of their own substeps (``groups``), bodies alone against the floor (``alone``) and sleeping islands
(``islands``); their limits are in ``tunables``, the contact law in ``contact_law``."""
