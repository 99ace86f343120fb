"""Offline analysis of UVMS recordings."""
