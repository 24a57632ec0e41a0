"""Video sources and writers (docs/architecture.md: open a file or an image-sequence folder).

``open_video(path)`` accepts

* a video file that OpenCV decodes (mp4, avi, ...);
* an image-sequence folder: ``img/*.jpg`` (OTB, LaSOT), ``color/*.jpg`` (VOT 2020+) or
  images directly in it (VOT up to 2019, GOT-10k);
* a clip folder: ``video.mp4`` (synthetic clips) or the one video file it holds.

Frames come as ``(index, frame)`` with ``frame`` a ``uint8`` BGR array of shape
``(H, W, 3)``; ``frame_count``, ``fps`` and ``size`` are known up front where the
container says. An image folder's frames are read in natural order (``frame2`` before
``frame10``; :class:`FrameOrderWarning` where the names leave it ambiguous) and must share one
size. A frame that fails to decode is skipped (its index is not yielded; ``vistrack run``
gives it a row of its own) and counted in a :class:`VideoDecodeWarning`; a path that is
missing, not a video, or holds no frame raises :class:`VideoError` with one
clear sentence.
"""

from __future__ import annotations

import os
import warnings
from contextlib import contextmanager
from pathlib import Path

import cv2
import numpy as np

from .clip_files import (  # the names' home; find_groundtruth, groundtruth_origin re-exported (__all__)
    FRAME_FOLDERS,
    IMAGE_EXT,
    TEXT_EXT,
    VIDEO_EXT,
    find_groundtruth,
    groundtruth_origin,
)
from .numbers import parse_float
from .video_errors import FrameOrderWarning, VideoDecodeWarning, VideoError, quoted
from .video_writer import VideoWriter  # the writer's home; re-exported (__all__)

# FFmpeg's own lines for a damaged stream ("header damaged", one per packet) are noise: a skipped
# frame is counted and reported once (VideoDecodeWarning). Read when the first capture opens.
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")

__all__ = ["is_stream", "VideoError", "VideoDecodeWarning", "FrameOrderWarning", "natural_key", "read_text_lines",
           "VideoSource", "open_video", "VideoWriter", "read_rects", "find_groundtruth", "groundtruth_origin",
           "prefetch"]


@contextmanager
def _opencv_quiet(on=True):
    """OpenCV's own log lines (``[ WARN:0] ... can't open camera by index``) left out within the block
    (``on``); the level is restored after."""
    level = cv2.utils.logging.getLogLevel() if on else None
    if on:
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
    try:
        yield
    finally:
        if on:
            cv2.utils.logging.setLogLevel(level)


class VideoSource:
    """An opened video: iterate for ``(index, frame)``.

    Attributes
    ----------
    path : Path
    shown : str
        How messages name it: the path, or a URL or stream as given (never ``http:/``).
    frame_count : int or None
        Number of frames if the container says (always known for image folders).
    fps : float
        Frames per second (30 for image folders, as in the data manifest).
    size : tuple of int
        ``(width, height)``.
    """

    def __init__(self, path, *, _images=None, remote=None):
        self.path = Path(path)
        self.shown = str(path) if is_stream(path) or "://" in str(path) else str(self.path)
        self._images = _images
        #: how a URL was read (:class:`~vistrack.io.remote.Remote`), or ``None``
        self.remote = remote
        # what cv2.VideoCapture opens: the file, a URL (kept whole) or a camera's index
        self._open_arg = stream_source(path) if is_stream(path) or "://" in str(path) else str(self.path)
        #: indices of the frames the last iteration skipped (failed to decode)
        self.skipped = []
        #: where the last iteration of a video stopped decoding before the frame count its container
        #: announces (``None`` when it reached it)
        self.ended_at = None
        if _images is not None:  # the frame size is the first readable image's (unreadable ones: "decode" rows)
            first = next((f for f in (cv2.imread(str(p), cv2.IMREAD_COLOR) for p in _images) if f is not None), None)
            if first is None:
                raise VideoError(f"{_images[0]} is not a readable image" if len(_images) == 1 else
                                 f"{Path(path)}: none of its {len(_images)} images is readable")
            self.frame_count = len(_images)
            self.fps = 30.0
            self.size = (first.shape[1], first.shape[0])
            return
        with _opencv_quiet(isinstance(self._open_arg, int)):  # no camera: the one error line below, not OpenCV's
            cap = cv2.VideoCapture(self._open_arg)
        try:
            ok, frame = cap.read() if cap.isOpened() else (False, None)
            if not ok or frame is None:
                if str(path).isdigit():
                    raise VideoError(f"cannot read {path}: no camera with that index (and no file or folder "
                                     f"named {path} here)")
                if "://" in str(path):
                    raise VideoError(f"cannot read {path}: not a video or stream OpenCV's FFmpeg can open, or it "
                                     "sent no frame")
                raise VideoError(f"{self.path} is not a video OpenCV can decode, or it has no frames")
            n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
            self.frame_count = n if n > 0 else None
            fps = cap.get(cv2.CAP_PROP_FPS)
            self.fps = float(fps) if fps and fps > 0 else 30.0
            self.size = (frame.shape[1], frame.shape[0])
        finally:
            cap.release()

    @property
    def exact_count(self):
        """Whether :attr:`frame_count` is exact: an image folder's is; a container's is what its header
        says (frames may be fewer, or more)."""
        return self._images is not None

    def __len__(self):
        if self.frame_count is None:
            raise TypeError("frame count unknown for this container")
        return self.frame_count

    #: a video's decoding gives up after this many failed frames in a row (before the announced end)
    max_failed_run = 25

    def __iter__(self):
        """``(index, frame)`` pairs. A frame that fails to decode is skipped (its index is not
        yielded: indices stay those of the stream, so ground truth stays aligned) and tracking
        goes on with the next decodable one; :attr:`skipped` counts them and a
        :class:`VideoDecodeWarning` at the end says how many. A video gives up after
        :attr:`max_failed_run` failures in a row."""
        self.skipped = []
        self.ended_at = None
        if self._images is not None:
            for i, p in enumerate(self._images):
                frame = cv2.imread(str(p), cv2.IMREAD_COLOR)
                if frame is None:
                    self.skipped.append(i)
                    continue
                if (frame.shape[1], frame.shape[0]) != self.size:
                    raise VideoError(f"{p.name} (frame {i}) is {frame.shape[1]}x{frame.shape[0]}, but the folder's "
                                     f"first frame is {self.size[0]}x{self.size[1]}: the frames of an image "
                                     "sequence must share one size")
                yield i, frame
            self._warn_skipped(len(self._images))
            return
        cap = cv2.VideoCapture(self._open_arg)
        try:
            i, failed = 0, 0
            while True:
                ok, frame = cap.read()
                if ok:
                    if failed:
                        self.skipped.extend(range(i - failed, i))
                    failed = 0
                    yield i, frame
                elif self.frame_count is not None and i < self.frame_count - 1 and failed < self.max_failed_run:
                    failed += 1
                else:
                    break
                i += 1
            i -= failed
            if self.frame_count is not None and i < self.frame_count:
                self.ended_at = i
                warnings.warn(f"{self.path.name}: decoding stopped at frame {i} of {self.frame_count}",
                              VideoDecodeWarning, stacklevel=2)
            self._warn_skipped(self.frame_count)
        finally:
            cap.release()

    def _warn_skipped(self, total):
        if self.skipped:
            k = self.skipped
            warnings.warn(f"{self.path.name}: {len(k)} frame(s) of {total} failed to decode and were skipped "
                          f"(frames {', '.join(map(str, k[:10]))}{', ...' if len(k) > 10 else ''})",
                          VideoDecodeWarning, stacklevel=3)


def natural_key(name):
    """Sort key of a file name by the numbers in it: ``frame2`` before ``frame10``; text parts
    compare as text (case-folded), number parts as numbers."""
    import re

    return tuple((0, int(t), "") if t.isdigit() else (1, 0, t.casefold())
                 for t in re.split(r"(\d+)", name) if t)


def _image_files(folder):
    """The image files of ``folder`` in natural order (:func:`natural_key`: ``frame1, frame2, ..,
    frame10``, not ``frame1, frame10, frame2``); a :class:`FrameOrderWarning` when two names give
    the same numbers (``1.png`` and ``01.png``) or the names differ in more than their numbers
    (the order is then a guess)."""
    files = [p for p in Path(folder).iterdir() if p.suffix.lower() in IMAGE_EXT and p.is_file()]
    files.sort(key=lambda p: (natural_key(p.name), p.name))
    keys = [natural_key(p.name) for p in files]
    dup = next((files[k] for k in range(1, len(keys)) if keys[k] == keys[k - 1]), None)
    stems = {tuple(t[2] for t in k) for k in keys}
    if dup is not None or len(stems) > 1:
        why = (f"{dup.name} and another name give the same frame number" if dup is not None
               else "the names differ in more than their numbers ("
               + ", ".join(sorted({files[0].name, files[-1].name})) + ")")
        warnings.warn(f"{folder}: the frames' order is ambiguous ({why}); read in natural order "
                      f"{files[0].name}, {files[1].name}, ...", FrameOrderWarning, stacklevel=3)
    return files


#: URL schemes of live streams, read by OpenCV (FFmpeg) as they come
STREAM_SCHEMES = ("rtsp://", "rtsps://", "rtmp://", "udp://", "tcp://", "srt://")
#: an HTTP(S) URL of one of these is a live playlist (HLS, DASH), read as a stream too
PLAYLIST_EXT = {".m3u8", ".mpd"}


def is_stream(path):
    """Whether ``path`` is a camera's index (``"0"``...; a file or folder of that name wins) or a live
    stream (``rtsp://``, ``udp://``..., an HTTP(S) ``.m3u8``/``.mpd`` playlist), read as it comes."""
    s = str(path)
    if s.isdigit():
        return not os.path.exists(s)
    low = s.lower()
    if low.startswith(STREAM_SCHEMES):
        return True
    if low.startswith(("http://", "https://")):
        tail = low.split("?", 1)[0].rsplit("/", 1)[-1]
        return os.path.splitext(tail)[1] in PLAYLIST_EXT
    return False


def stream_source(path):
    """What :class:`cv2.VideoCapture` opens for a stream: a camera's index as an int, else the URL."""
    s = str(path)
    return int(s) if s.isdigit() else s


def open_video(path):
    """Open a video file, an image-sequence folder or a clip folder (see module doc), a camera by its
    index (``"0"``; a local path wins) or a live stream (:func:`is_stream`). URLs of files:
    :func:`vistrack.io.clips.load_clip`."""
    if is_stream(path):
        return VideoSource(str(path))
    p = Path(str(path)[len("file://"):] if str(path).startswith("file://") else path)
    if not p.exists():
        raise VideoError(f"{p} does not exist")
    if not p.is_file() and not p.is_dir():
        raise VideoError(f"{p} is not a regular file or folder (a device or pipe): give a video file or an image "
                         "folder")
    if p.is_file():
        if os.path.getsize(p) == 0:
            raise VideoError(f"{p} is empty")
        if p.suffix.lower() in TEXT_EXT:
            raise VideoError(f"{p} is a {p.suffix} file, not a video (FFmpeg would render its text as frames)")
        return VideoSource(p)
    for sub in FRAME_FOLDERS:
        if (p / sub).is_dir() and _image_files(p / sub):
            return VideoSource(p, _images=_image_files(p / sub))
    if (p / "video.mp4").is_file():
        return VideoSource(p / "video.mp4")
    videos = sorted(q for q in p.iterdir() if q.suffix.lower() in VIDEO_EXT)
    if len(videos) == 1:
        return VideoSource(videos[0])
    images = _image_files(p)
    if images:
        return VideoSource(p, _images=images)
    if len(videos) > 1:
        raise VideoError(f"{p} holds several videos ({', '.join(v.name for v in videos)}); name one")
    others = sorted({q.suffix.lower() for d in (p, *(p / f for f in FRAME_FOLDERS)) if d.is_dir() for q in d.iterdir()
                     if q.suffix})
    raise VideoError(f"{p} holds no video and no images (in the folder, img/ or color/: images "
                     f"{', '.join(sorted(IMAGE_EXT))}; videos {', '.join(sorted(VIDEO_EXT))})"
                     + (f"; it holds {', '.join(others[:5])} files" if others else ""))


def read_rects(path, origin=0):
    """Boxes ``(n, 4)`` as 0-based ``x, y, w, h`` from a ground-truth text file, one frame per line
    (comma, tab or space separated).

    A line is a rectangle ``x, y, w, h`` (OTB, GOT-10k, LaSOT, VOT rectangles) or a polygon of 4
    corners ``x1, y1, .., x4, y4`` (VOT), read as its axis-aligned bounding box. A frame without
    the object — ``NaN`` values, ``0,0,0,0`` or a non-positive size — becomes ``0, 0, 0, 0``
    (not visible). ``origin=1``: the file's pixel coordinates start at 1 (OTB, LaSOT), and one is
    subtracted from ``x`` and ``y``. Any other line is a :class:`VideoError` naming the file and line.
    """
    rows = []
    for k, line in enumerate(read_text_lines(path), 1):
        line = line.strip()
        if not line:
            continue
        parts = line.replace(",", " ").replace("\t", " ").split()
        try:
            v = np.array([parse_float(x) for x in parts])
        except ValueError:
            raise VideoError(f"{path}, line {k}: expected numbers (x,y,w,h or a 4-corner polygon), "
                             f"got {quoted(line)}") from None
        if np.any(np.abs(v[np.isfinite(v)]) > MAX_COORD):
            raise VideoError(f"{path}, line {k}: a value beyond {MAX_COORD:.0e} px is not a pixel coordinate, "
                             f"got {quoted(line)}")
        if len(v) == 8:
            xs, ys = v[0::2], v[1::2]
            v = np.array([xs.min(), ys.min(), xs.max() - xs.min(), ys.max() - ys.min()])
        elif len(v) != 4:
            raise VideoError(f"{path}, line {k}: expected 4 values x,y,w,h or 8 (a polygon), got {len(v)}")
        if not (np.all(np.isfinite(v)) and v[2] > 0 and v[3] > 0):
            v = np.zeros(4)  # the object is not in view
        else:
            v[:2] -= origin
        rows.append(v)
    return np.array(rows, dtype=float).reshape(-1, 4)


#: the largest pixel coordinate or size a ground-truth or results file may give
MAX_COORD = 1e6


def read_text_lines(path):
    """The lines of a text file (UTF-8, a byte-order mark ignored); a :class:`VideoError` naming the
    file for one that is not text (binary) or cannot be read."""
    try:
        with open(path, encoding="utf-8-sig") as f:
            return f.read().splitlines()
    except UnicodeDecodeError as e:
        raise VideoError(f"{path} is not a text file (byte {e.start} is not UTF-8)") from None
    except IsADirectoryError:
        raise VideoError(f"{path} is a folder, not a text file") from None


def prefetch(frames, size=8):
    """The items of ``frames`` (e.g. a :class:`VideoSource`), decoded ahead in a background thread
    into a queue of at most ``size``: decoding overlaps tracking (OpenCV releases the GIL while it
    decodes). Same items, same order; an exception in the decoder is raised here (its warnings
    are issued from the decoding thread); closing the generator stops the thread."""
    import queue
    import threading

    q = queue.Queue(maxsize=size)
    stop = threading.Event()
    done = object()

    def work():
        try:
            for item in frames:
                while not stop.is_set():
                    try:
                        q.put(("item", item), timeout=0.1)
                        break
                    except queue.Full:
                        continue
                if stop.is_set():
                    return
            q.put(("end", done))
        except BaseException as e:  # noqa: BLE001 - handed to the consumer, which raises it
            q.put(("error", e))

    t = threading.Thread(target=work, name="vistrack-decode", daemon=True)
    t.start()
    try:
        while True:
            kind, value = q.get()
            if kind == "item":
                yield value
            elif kind == "error":
                raise value
            else:
                return
    finally:
        stop.set()
        while t.is_alive():
            try:
                q.get_nowait()
            except queue.Empty:
                t.join(0.05)

