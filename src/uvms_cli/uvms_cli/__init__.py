"""The uvms command."""
