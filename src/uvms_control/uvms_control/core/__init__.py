"""Pure cores of the unified force controller and its contact tasks (no ROS).

``law``: the control laws, the switch and the references they follow; ``task``: contact
tasks around the control step (goal checks, limits, supervisor, results). ``task`` imports
``law``, never the other way round; both import the shared modules here (errors, parameter
specs and parameters, the fuzzy sets those build).
"""
