"""uvms tune: the controller's gains by constrained Bayesian optimization (Optuna) over scenarios run on Ray."""
