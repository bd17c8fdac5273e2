"""The detector's core: recursive least squares, the GLRT and the self-tuning residual
generators (Blanke & Hansen). No ROS here."""
