"""Reproductions of the seeds' experiments (thesis 001 §4.5.5, ...)."""
