"""uvms_model package."""
