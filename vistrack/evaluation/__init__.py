"""``eval``: its experiment (tasks, runner, scores) and its pipeline."""
