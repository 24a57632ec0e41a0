"""What reading and writing videos raise and warn (re-exported by :mod:`vistrack.io.video`)."""

from __future__ import annotations

__all__ = ["VideoError", "VideoDecodeWarning", "FrameOrderWarning"]


class VideoError(ValueError):
    """The path cannot be opened as a video source."""


class VideoDecodeWarning(RuntimeWarning):
    """A frame failed to decode before the announced end of the stream."""


class FrameOrderWarning(UserWarning):
    """The names of an image folder's frames do not give one clear order."""
