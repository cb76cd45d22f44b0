"""The robust solver of one box against the floor, a module a stage (the script: ``stages.FLOOR_STEP``,
``stages.FLOOR_PIECE``): ``robust_solver`` the grid step (flight in closed form, impacts located in time, contact
steps, sleep) and its kernel; ``flight`` (closed-form flight to the first contact), ``restitution`` (restitution),
``contact_step`` (a contact step: find contacts, integrate velocities, locate impacts, store impulses, integrate
positions), ``contact_solver`` (solve contacts: the corners' LCP, and the penalty's implicit correction),
``energy_limit`` (energy limit), ``penalty`` (relax) and ``memory`` (what a box carries between calls)."""
