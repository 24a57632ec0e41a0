"""Writing videos: :class:`VideoWriter` (the annotated ``--out`` video, the synthetic and stressed
clips), H.264 through PyAV where it can, a codec the container holds, written whole."""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np

from .video_errors import VideoError

__all__ = ["VideoWriter", "CONTAINERS"]

#: containers VideoWriter writes and what it puts in them under codec "auto"/"h264"
CONTAINERS = {".mp4": "h264", ".m4v": "h264", ".mov": "h264", ".mkv": "h264", ".avi": "mjpg"}


class VideoWriter:
    """Write BGR (or grey) ``uint8`` frames to an mp4, as a context manager.

    Parameters
    ----------
    path : str or Path
    fps : float
    size : tuple of int
        ``(width, height)``; every frame must have it.
    codec : {"mp4v", "h264", "auto"}
        ``mp4v`` (MPEG-4 Part 2, OpenCV; the synthetic clips, whose decoded pixels the
        experiments depend on); ``h264`` through PyAV (libx264, ``yuv420p``: plays in browsers
        and Jupyter; an odd width or height is padded by one pixel); ``auto``: H.264 where PyAV
        can write it, else mp4v with :attr:`note` saying so. The container is the file name's
        (:data:`CONTAINERS`): ``.mp4``/``.m4v``/``.mov`` get their index first (``faststart``: a
        browser plays them while they load), ``.mkv`` H.264 too, and ``.avi`` Motion JPEG under
        ``h264``/``auto`` (with :attr:`note`); any other name is a :class:`VideoError`.
    atomic : bool
        Write under a temporary name beside ``path`` (:func:`vistrack.io.outputs.temporary_name`),
        renamed over it by :meth:`close`, holding ``path``'s lock meanwhile
        (:class:`vistrack.io.outputs.OutputLock`: a second writer is refused); ``path`` never
        holds half a video and is never the same file as another writer's.

    Attributes
    ----------
    codec : str
        The codec written.
    note : str or None
        Why H.264 was not written, under ``codec="auto"``.
    """

    def __init__(self, path, fps, size, codec="mp4v", atomic=False):
        from .outputs import OutputLock, is_device, temporary_name

        self.path = Path(path)
        if not self.path.parent.is_dir():
            raise VideoError(f"cannot write {self.path}: folder {self.path.parent} does not exist")
        if codec not in ("mp4v", "h264", "auto"):
            raise ValueError(f"codec must be mp4v, h264 or auto, got {codec!r}")
        self.size = tuple(int(v) for v in size)
        self.frames = 0
        self.note = None
        self._av = None
        # the container by the name's last known suffix (``a.mp4``, or a temporary ``a.mp4.part-7``)
        suffix = next((x for x in reversed([x.lower() for x in self.path.suffixes]) if x in CONTAINERS), "")
        self.container = suffix = suffix or (".mp4" if is_device(self.path) else "")  # /dev/null: anything goes
        if suffix not in CONTAINERS:
            raise VideoError(f"cannot write a video to {self.path}: give a file name ending in "
                             f"{', '.join(CONTAINERS)}")
        self._w = _Closed()
        # atomic: written under a temporary name of its own, renamed over ``path`` by close(); one live writer
        self._lock = OutputLock(self.path, "annotated video") if atomic else _NoLock()
        self._final = self.path
        try:
            if atomic and not is_device(self.path):
                self.path = temporary_name(self.path)
            self._open(fps, codec)
        except BaseException:
            self._discard()
            raise

    def _discard(self):
        if self.path != self._final:
            self.path.unlink(missing_ok=True)
        self._lock.release()

    def _open(self, fps, codec):
        if codec in ("h264", "auto") and CONTAINERS[self.container] == "mjpg":
            self.codec = "mjpg"  # H.264 in AVI plays in few players: AVI's own Motion JPEG
            self.note = f"{self.container} holds Motion JPEG here (.mp4 or .mkv for H.264)"
            self._w = cv2.VideoWriter(str(self.path), cv2.VideoWriter_fourcc(*"MJPG"), float(fps), self.size)
            if not self._w.isOpened():
                raise VideoError(f"cannot open {self._final} for writing")
            return
        if codec in ("h264", "auto"):
            try:
                self._open_h264(fps)
                self.codec = "h264"
                return
            except Exception as e:  # PyAV missing, or FFmpeg without an H.264 encoder
                if codec == "h264":
                    raise VideoError(f"cannot write H.264 to {self._final}: {e}") from None
                self.note = (f"H.264 not available ({type(e).__name__}: {e}); wrote MPEG-4 Part 2 (mp4v), which "
                             "browsers do not play (pip install av)")
        self.codec = "mp4v"
        self._w = cv2.VideoWriter(str(self.path), cv2.VideoWriter_fourcc(*"mp4v"), float(fps), self.size)
        if not self._w.isOpened():
            hint = "" if self._final.suffix.lower() == ".mp4" else " (give a file name ending in .mp4)"
            raise VideoError(f"cannot open {self._final} for writing{hint}")

    def _open_h264(self, fps):
        from fractions import Fraction

        import av  # noqa: PLC0415  (optional: PyAV)

        # the index (moov) first, so that a browser plays the file while it loads
        fmt = {".mp4": "mp4", ".m4v": "mp4", ".mov": "mov", ".mkv": "matroska"}[self.container]
        options = {"movflags": "+faststart"} if fmt in ("mp4", "mov") else {}
        container = av.open(str(self.path), "w", format=fmt, options=options)
        try:
            stream = container.add_stream("libx264", rate=Fraction(fps).limit_denominator(1001))
            stream.width, stream.height = (v + v % 2 for v in self.size)
            stream.pix_fmt = "yuv420p"
        except Exception:
            container.close()
            raise
        self._av = (av, container, stream)

    def write(self, frame):
        """Append one frame, ``(H, W, 3)`` BGR or ``(H, W)`` grey, of the video's :attr:`size`."""
        if (frame.shape[1], frame.shape[0]) != self.size:
            raise ValueError(f"frame size {frame.shape[1]}x{frame.shape[0]} != video size "
                             f"{self.size[0]}x{self.size[1]}")
        if frame.ndim == 2:
            frame = cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
        frame = np.ascontiguousarray(frame, dtype=np.uint8)
        if self._av is None:
            self._w.write(frame)
        else:
            av, container, stream = self._av
            h, w = frame.shape[:2]
            if w % 2 or h % 2:
                frame = cv2.copyMakeBorder(frame, 0, h % 2, 0, w % 2, cv2.BORDER_REPLICATE)
            for packet in stream.encode(av.VideoFrame.from_ndarray(frame, format="bgr24")):
                container.mux(packet)
        self.frames += 1

    def close(self):
        """Flush the encoder, close the file and rename it over the output path (a video without
        frames is removed; the path is left as it was)."""
        if self._lock is None:
            return
        try:
            if self._av is None:
                self._w.release()
            else:
                av, container, stream = self._av
                self._av = None
                try:
                    for packet in stream.encode():
                        container.mux(packet)
                finally:
                    container.close()
                self._w = _Closed()
        finally:  # the frames written so far are kept even when the encoder fails to flush (a full disk)
            try:
                if self.path != self._final:
                    if self.frames:
                        os.replace(self.path, self._final)
                    else:
                        self.path.unlink(missing_ok=True)
                    self.path = self._final
            finally:
                self._lock.release()
                self._lock = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class _NoLock:
    def release(self):
        pass


class _Closed:
    def release(self):
        pass
