"""uvms pilot: a person's inputs (terminal keys, a gamepad) onto the pilot topics (issue 51)."""
