"""The core: particle sets, resampling, Gaussians, the step's kernel ``K`` / ``p_0``, per-frame
feature maps, the metrics and process settings. It imports numpy, scipy, OpenCV, numba and
:mod:`vistrack.kernels` only."""
