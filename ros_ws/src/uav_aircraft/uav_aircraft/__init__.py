"""The aircraft the project flies and models: one folder each, and what reads it."""
