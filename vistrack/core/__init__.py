"""The particle core: particle sets, resampling, Gaussians, the step's kernel ``K`` / ``p_0``, the
optional hooks and the random streams. It imports numpy and scipy only."""
