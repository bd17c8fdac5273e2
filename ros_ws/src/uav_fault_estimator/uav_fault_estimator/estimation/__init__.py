"""The estimator's core: residuals and sensitivities, fault models, the MAP QP, its solver,
the arrival cost, the noise model and the moving-horizon and batch estimators. No ROS here."""
