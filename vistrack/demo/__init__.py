"""``vistrack demo``: its clip, its comparisons and the real-clip step."""
