"""Synthetic data with exact ground truth (bearings sequences; video clips to come)."""
