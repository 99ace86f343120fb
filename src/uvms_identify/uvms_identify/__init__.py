"""uvms identify: the vehicle's hydrodynamics from its own recordings (issue 50)."""
