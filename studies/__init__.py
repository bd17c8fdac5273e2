"""Studies that measure the diagnosis over many simulated flights (python -m studies.NAME)."""
