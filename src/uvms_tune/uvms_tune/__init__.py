"""uvms tune: the controller gains by constrained Bayesian optimization over scenarios."""
