"""Thruster allocation (eq. 10), Healey thruster dynamics (eq. 11-15) and their kernels, fault injection and detection, and the thruster_allocator node."""
