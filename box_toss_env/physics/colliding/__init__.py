"""The robust solver for boxes that collide, a module a stage: the step script (``step``), pairs
(``broadphase``), contacts (``narrowphase``), the contact solve, warm start and penalty
(``colliding_solver``, with the exact Coulomb solve ``joint_contact_solve``) and sleeping islands
(``islands``)."""
