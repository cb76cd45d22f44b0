"""The robust solver of one box against the floor, a module a stage: ``robust_solver`` the script (flight in closed
form, impacts located in time, contact steps, sleep) and its kernel; ``flight`` (closed-form flight to the first
contact), ``restitution`` (0. impacts), ``contact_step`` (one contact step: prepare, 1. integrate velocities,
3. locate impacts, store impulses, 5. integrate positions), ``contact_solver`` (2. solve contacts: the corners'
LCP, and the penalty's implicit correction), ``energy_limit`` (4.), ``penalty`` (6. relax) and ``memory`` (what a
box carries between calls)."""
