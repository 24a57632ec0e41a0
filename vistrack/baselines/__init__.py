"""The trackers vistrack is compared with (OpenCV's, NanoTrack v3 with its authors' logic), each a function that
tracks a clip's frames from a box;
the registry lists them by name (:data:`vistrack.registry.baseline_specs.BASELINES`)."""

from .nanotrack import NanoTrackV3, track_nanotrack_v3
from .opencv import check_opencv, track_opencv

__all__ = ["check_opencv", "track_opencv", "NanoTrackV3", "track_nanotrack_v3"]
