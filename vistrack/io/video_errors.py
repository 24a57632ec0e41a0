"""What reading and writing videos raise and warn (re-exported by :mod:`vistrack.io.video`), and how an
error line quotes what it read."""

from __future__ import annotations

__all__ = ["VideoError", "VideoDecodeWarning", "FrameOrderWarning", "quoted"]


class VideoError(ValueError):
    """The path cannot be opened as a video source."""


class VideoDecodeWarning(RuntimeWarning):
    """A frame failed to decode before the announced end of the stream."""


class FrameOrderWarning(UserWarning):
    """The names of an image folder's frames do not give one clear order."""


def quoted(text, most=60):
    """``text`` (any value, as ``str``) quoted, cut to ``most`` characters: an error line stays one short line."""
    text = str(text)
    return repr(text if len(text) <= most else text[:most] + "...")
