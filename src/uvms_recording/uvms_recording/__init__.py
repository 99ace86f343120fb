"""Recording and replay of the UVMS graph."""
