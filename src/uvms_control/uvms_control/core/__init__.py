"""Pure cores of the unified force controller and the thruster allocator (no ROS)."""
