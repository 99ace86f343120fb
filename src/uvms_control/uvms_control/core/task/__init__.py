"""Contact tasks around the control step: goal, checks, limits, supervisor and results."""
