"""The seed scheme, the reference text's own method: one box against the floor (``reference_solver``) and our
extension of it to boxes that collide (``colliding_reference``)."""
