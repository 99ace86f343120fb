"""Viewing the UVMS."""
