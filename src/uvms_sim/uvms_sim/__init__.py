"""uvms_sim package."""
