"""Writing videos: :class:`VideoWriter` (the annotated ``--out`` video, the synthetic and stressed
clips), H.264 through PyAV where it can, a codec the container holds, written whole."""

from __future__ import annotations

import errno
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
        renamed over it by :meth:`close` once the encoder flushed and the file closed, holding
        ``path``'s lock meanwhile (:class:`vistrack.io.outputs.OutputLock`: a second writer is
        refused); ``path`` never holds half a video and is never the same file as another writer's.
    what : str or None
        What the video is, for errors and the lock ("annotated video" when ``atomic``, else "video").

    Raises
    ------
    vistrack.io.outputs.OutputError
        From :meth:`write` or :meth:`close` when the video cannot be written whole (a full disk,
        a failed flush or close, a file OpenCV's writer left unplayable): it names ``path`` and the
        cause; the temporary (or, not atomic, the broken) file is removed and an earlier ``path``
        is left as it was. A device (``/dev/null``) is written directly and its own error raised.

    Attributes
    ----------
    codec : str
        The codec written.
    note : str or None
        Why H.264 was not written, under ``codec="auto"``.
    """

    def __init__(self, path, fps, size, codec="mp4v", atomic=False, what=None):
        from .outputs import OutputLock, check_not_input, output_target, temporary_name

        self.path = Path(path)
        self.what = what or ("annotated video" if atomic else "video")
        check_not_input(self.path, self.what)
        # a link is written through to its file; a device or pipe (/dev/null, /dev/stdout) in place
        self._target, direct = output_target(self.path)
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
        self.container = suffix = suffix or (".mp4" if direct else "")  # /dev/null: anything goes
        if suffix not in CONTAINERS:
            raise VideoError(f"cannot write a video to {self.path}: give a file name ending in "
                             f"{', '.join(CONTAINERS)}")
        self._w = _Closed()
        self._error = None  # the first write that failed: close() then discards the file
        self._complete = True  # False: the run failed (abandon)
        # atomic: written under a temporary name of its own, renamed over ``path`` by close(); one live writer
        self._lock = OutputLock(self._target, self.what) if atomic else _NoLock()
        self._final = self.path
        self._earlier = self._target.is_file()
        self._atomic = atomic and not direct
        self._device = direct
        try:
            if self._atomic:
                self.path = temporary_name(self._target)
            self._open(fps, codec)
        except OSError as e:  # the temporary file or the container could not be created (a full disk)
            self._discard()
            raise self._failure(e) from None
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
            except Exception as e:  # noqa: BLE001 - PyAV missing, or FFmpeg without an H.264 encoder
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

        import av  # optional: PyAV

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
        if self._error is not None:
            raise self._failure(self._error)
        if self._av is None:
            self._w.write(frame)
        else:
            av, container, stream = self._av
            h, w = frame.shape[:2]
            if w % 2 or h % 2:
                frame = cv2.copyMakeBorder(frame, 0, h % 2, 0, w % 2, cv2.BORDER_REPLICATE)
            try:
                for packet in stream.encode(av.VideoFrame.from_ndarray(frame, format="bgr24")):
                    container.mux(packet)
            except OSError as e:  # the disk is full: the video cannot be whole any more
                self._error = e
                raise self._failure(e) from None
        self.frames += 1

    def abandon(self):
        """The run writing this video failed: :meth:`close` keeps an earlier file at the path."""
        self._complete = False

    def close(self):
        """Flush the encoder, close the file and, when both succeeded, rename it over the output
        path (a video without frames is removed; the path is left as it was). On a failure,
        here or in an earlier :meth:`write`, the file is removed, the path left as it was, and
        :class:`~vistrack.io.outputs.OutputError` raised (once: not again after :meth:`write` raised it).
        After :meth:`abandon` an earlier file at the path is kept."""
        if self._lock is None:
            return
        error, said = self._error, self._error is not None
        keep_earlier = not self._complete and self._earlier
        try:
            try:
                self._finish()
                if error is None and self.frames and self.path != self._final and not keep_earlier:
                    os.replace(self.path, self._target)
            except Exception as e:  # noqa: BLE001 - any failure to flush, close or rename: the file is not whole
                error = error or e
        finally:
            if self.path != self._final or (error is not None and not self._device):
                self.path.unlink(missing_ok=True)  # the temporary file (renamed, or not to be), or a broken one
            self.path = self._final
            self._lock.release()
            self._lock = None
        if error is not None and not said:
            raise self._failure(error)

    def _finish(self):
        """Flush the encoder and close the file; a file OpenCV's writer left unplayable (it says
        nothing when a write fails) raises ``OSError``."""
        if self._av is None:
            self._w.release()
            self._w = _Closed()
            if self.frames and not self._device:
                _check_playable(self.path, self.frames)
            return
        av, container, stream = self._av
        self._av = None
        try:
            for packet in stream.encode():
                container.mux(packet)
        finally:
            container.close()

    def _failure(self, cause):
        """The error of a failed write: :class:`~vistrack.io.outputs.OutputError` naming the
        output and the cause (a device: its own error)."""
        from .outputs import OutputError, left_note

        if self._device:
            return cause
        return OutputError(self.what, self._final, cause, left_note(self._final, self._earlier and self._atomic))

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.close()
            return
        # the run failed (an error, Ctrl-C, SIGTERM): an earlier file is kept, and a failure to close this
        # one (a file cut short is removed) does not hide the error that ended the run
        self.abandon()
        try:
            self.close()
        except Exception:  # noqa: BLE001 - the error that ended the run is the one to raise
            pass


def _check_playable(path, frames):
    """Raise ``OSError`` unless OpenCV opens the video at ``path``, counts ``frames`` frames and
    decodes the last one (the count is in the header or index, the last frame at the end: a file
    cut short by a full disk fails one or the other)."""
    cap = cv2.VideoCapture(str(path))
    try:
        n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) if cap.isOpened() else -1
        ok = n == frames and cap.set(cv2.CAP_PROP_POS_FRAMES, frames - 1) and cap.read()[0]
    finally:
        cap.release()
    if ok:
        return
    if os.statvfs(path.parent).f_bavail == 0:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    raise OSError(errno.EIO, f"the file OpenCV wrote does not play back its {frames} frames (a full disk?)")


class _NoLock:
    def release(self):
        pass


class _Closed:
    def release(self):
        pass
