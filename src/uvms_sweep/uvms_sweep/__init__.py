"""Parameter sweeps of UVMS scenarios on Ray."""
