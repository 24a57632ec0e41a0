"""The trackers vistrack is compared with (OpenCV's), each a function that tracks a clip's frames from a box;
the registry lists them by name (:data:`vistrack.registry.baseline_specs.BASELINES`)."""

from .opencv import check_opencv, track_opencv

__all__ = ["check_opencv", "track_opencv"]
