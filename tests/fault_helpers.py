"""Shared by the fault tests (``tests/*/test_faults_*.py``, filed by what a fault breaks): small inputs
(videos, image folders, OTB clips, frames for the Python API), readers of what a run wrote, the check
that a command ended in one clear error line, and the pieces the tests share with the soak
(``benchmarks/soak.py``): a full disk on a small tmpfs, a TraX session driven by vot-trax's own
client, Ctrl-C at a command's start-up or shut-down."""

from __future__ import annotations

import csv

import cv2
import numpy as np
from full_disk import Unavailable, on_tmpfs  # benchmarks/, on pytest's pythonpath
from soak_harness import damage_copy, decoded_frames, looping_server
from soak_trax import INTERRUPT_AT, trax_session

__all__ = ["H", "W", "INIT", "write_video", "read_rows", "box_frame", "image_folder", "avi", "one_error", "mp4",
           "decodable", "decoded_frames", "damage_copy", "looping_server", "clip_bytes", "moving_box_frames",
           "textured_frame", "textured_avi", "otb_folder", "api_frames", "api_track", "Unavailable", "on_tmpfs",
           "INTERRUPT_AT", "trax_session"]

H, W = 120, 160
#: a start box on the clips of :func:`write_video` and :func:`textured_avi`
INIT = "48,51,24,18"


def write_video(path, n, seed=0):
    """An MJPG ``.avi`` of ``n`` frames: a red box circling on a blurred noise background."""
    rng = np.random.default_rng(seed)
    bg = cv2.GaussianBlur(rng.normal(110, 40, (H, W, 3)).astype(np.float32), (0, 0), 2).clip(0, 255).astype(np.uint8)
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (W, H))
    for t in range(n):
        f = bg.copy()
        cx, cy = int(60 + 20 * np.sin(0.1 * t)), int(60 + 10 * np.cos(0.1 * t))
        cv2.rectangle(f, (cx - 12, cy - 9), (cx + 12, cy + 9), (30, 60, 220), -1)
        wr.write(f)
    wr.release()


def read_rows(path):
    """The rows of a CSV file as dicts."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def box_frame(i, w=W, h=H):
    """Frame ``i`` of a red box moving 2 px per frame on flat grey."""
    img = np.full((h, w, 3), 100, np.uint8)
    cv2.rectangle(img, (40 + 2 * i, 50), (64 + 2 * i, 68), (30, 60, 220), -1)
    return img


def image_folder(folder, n=8, names=None, ext="png"):
    """An OTB-style folder: ``img/`` of a red box moving 2 px per frame, ``groundtruth_rect.txt``
    (1-based); returns the 0-based truth ``(n, 4)``."""
    (folder / "img").mkdir(parents=True)
    names = names or [f"{i + 1:04d}.{ext}" for i in range(n)]
    for i, name in enumerate(names):
        cv2.imwrite(str(folder / "img" / name), box_frame(i))
    truth = np.array([[40 + 2 * i, 50, 25, 19] for i in range(len(names))], float)
    (folder / "groundtruth_rect.txt").write_text("".join(f"{x + 1:g},{y + 1:g},{w:g},{h:g}\n" for x, y, w, h in truth))
    return truth


def avi(path, n, w=W, h=H):
    """An MJPG ``.avi`` of ``n`` :func:`box_frame` frames (the box goes back every 40)."""
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (w, h))
    for i in range(n):
        wr.write(box_frame(i % 40, w, h))
    wr.release()


def one_error(code, err, *words):
    """Assert a non-zero exit with exactly one ``Error:`` line holding every one of ``words`` and no
    traceback; returns the line."""
    assert code not in (0, None) and "Traceback" not in err, err
    lines = [ln for ln in err.splitlines() if ln.startswith("Error:")]
    assert len(lines) == 1, err
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]


def mp4(path, n, faststart, size=(W, H)):
    """An MPEG-4 Part 2 ``.mp4`` of ``n`` noise frames through PyAV, its index first (``faststart``) or last."""
    import av

    c = av.open(str(path), "w", options={"movflags": "faststart"} if faststart else {})
    s = c.add_stream("mpeg4", rate=25)
    s.width, s.height, s.pix_fmt = *size, "yuv420p"
    rng = np.random.default_rng(0)
    for _ in range(n):
        frame = rng.integers(0, 255, (size[1], size[0], 3), dtype=np.uint8)
        for p in s.encode(av.VideoFrame.from_ndarray(frame, format="bgr24")):
            c.mux(p)
    for p in s.encode():
        c.mux(p)
    c.close()


def decodable(video):
    """How many of the first 100 reads of ``video`` OpenCV decodes (reading on past failures)."""
    cap = cv2.VideoCapture(str(video))
    n = sum(cap.read()[0] for _ in range(100))
    cap.release()
    return n


def clip_bytes(folder):
    """``{name: bytes}`` of the files of ``folder``."""
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def moving_box_frames(folder, n=8):
    """``n`` OTB image frames of a red box moving 2 px per frame into ``folder``; returns their
    ground-truth lines (1-based ``x,y,w,h``)."""
    folder.mkdir(parents=True)
    rows = []
    for i in range(n):
        img = np.full((H, W, 3), 100, np.uint8)
        cv2.rectangle(img, (40 + 2 * i, 50), (64 + 2 * i, 68), (30, 60, 220), -1)
        cv2.imwrite(str(folder / f"{i + 1:04d}.png"), img)
        rows.append(f"{41 + 2 * i},51,25,19")  # OTB: 1-based
    return rows


def textured_frame(i, w=W, h=H):
    """Frame ``i`` of a red box moving 1 px per frame (back every 40) on grey with stripes: an encoder
    has something to write."""
    img = np.full((h, w, 3), 100, np.uint8)
    img[::7] = 60  # texture: the encoder has something to write
    cv2.rectangle(img, (40 + i % 40, 50), (64 + i % 40, 68), (30, 60, 220), -1)
    return img


def textured_avi(path, n, w=W, h=H):
    """An MJPG ``.avi`` of ``n`` :func:`textured_frame` frames; returns ``path``."""
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (w, h))
    for i in range(n):
        wr.write(textured_frame(i, w, h))
    wr.release()
    return path


def otb_folder(folder, n, bad=()):
    """An OTB folder of ``n`` :func:`textured_frame` frames (the box 2 px per frame), the images of
    ``bad`` frames not images, and its 1-based ground truth."""
    (folder / "img").mkdir(parents=True)
    for i in range(n):
        img = textured_frame(2 * i)
        cv2.imwrite(str(folder / "img" / f"{i + 1:04d}.png"), img)
    for i in bad:
        (folder / "img" / f"{i + 1:04d}.png").write_bytes(b"not a png")
    (folder / "groundtruth_rect.txt").write_text("".join(f"{41 + 2 * i},51,25,19\n" for i in range(n)))
    return folder


def api_frames(n=5):
    """``n`` 120x90 BGR frames of a red box moving 2 px per frame on striped grey."""
    out = []
    for k in range(n):
        f = np.full((90, 120, 3), 50, np.uint8)
        f[::6] = 80
        cv2.rectangle(f, (30 + 2 * k, 30), (54 + 2 * k, 54), (40, 60, 230), -1)
        out.append(f)
    return out


def api_track(frames, box=(30, 30, 25, 25)):
    """The sub-pixel boxes ``vistrack.Tracker(seed=3, particles=50)`` gives over ``frames`` from ``box``."""
    import vistrack

    t = vistrack.Tracker(seed=3, particles=50)
    t.init(frames[0], box)
    return [t.box_estimate] + [t.update(f) and t.box_estimate for f in frames[1:]]
