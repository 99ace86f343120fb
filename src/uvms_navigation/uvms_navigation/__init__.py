"""Navigation: the estimator node and its pure error-state EKF core."""
