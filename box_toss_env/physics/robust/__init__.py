"""The robust solver of one box against the floor (``robust_solver``: flight in closed form, impacts located in
time, contact steps), its corner contacts (``contact_solver``) and the closed-form flight (``flight``)."""
