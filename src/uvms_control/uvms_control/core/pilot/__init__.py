"""The pilot's side of the controller: inputs, limits, deadman, modes and handover (pure)."""
