"""uvms_control package."""
