"""uvms_thrusters: thruster allocation (eq. 10), thruster dynamics (eq. 11-15), faults.

The allocation and Healey thruster dynamics with their kernels, fault injection and
detection (pure cores), and the thruster_allocator node around them.
"""
