"""Benchmarks of the project's stages (run from the repository root: python -m
benchmarks.NAME), and the reference and comparison QP solvers they and the tests share."""
