"""The robust solver for boxes that collide, a module a stage: the step script (``colliding_step``), pairs
(``broadphase``), contacts (``box_collision``, the narrowphase), the contact solve, warm start and penalty
(``colliding_solver``, with the exact Coulomb solve ``joint_contact_solve``) and sleeping islands
(``islands``)."""
