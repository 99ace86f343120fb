"""uvms_bringup package."""
