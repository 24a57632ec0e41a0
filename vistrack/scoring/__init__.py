"""Scores of tracks against ground truth and their summaries over runs."""
