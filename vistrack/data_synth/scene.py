"""Shared pieces of the synthetic video renderers: textures, clutter, lighting, blur, noise."""

from __future__ import annotations

import functools
import inspect
import json
import os
import shutil
from pathlib import Path

import cv2
import numpy as np

from vistrack.io.clip_files import CLIP_FILES, FRAME_FOLDERS, IMAGE_EXT, SYNTH_RECORDS, VIDEO_EXT
from vistrack.io.clips import write_track_csv

from .clip_sizes import check_clip_sizes

__all__ = ["smooth_noise", "clutter_background", "motion_blur", "lighting", "add_noise", "write_clip_files",
           "atomic_clip", "is_synth_clip", "out_folder", "prepare_suite", "check_video_size", "SuiteNames"]

#: names in a clip folder that a run reads as part of the clip: never carried from an old folder into a new clip
CLIP_NAMES = {*CLIP_FILES, *FRAME_FOLDERS}
#: the largest side MPEG-4 Part 2 (mp4v) encodes
MAX_SIDE = 8190


def smooth_noise(shape, rng, scale=8.0):
    """Gaussian-smoothed white noise in ``[0, 1]`` of ``shape (H, W)`` (feature size ``scale`` px)."""
    h, w = shape
    small = rng.random((max(2, int(h / scale)) + 2, max(2, int(w / scale)) + 2)).astype(np.float32)
    big = cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)
    lo, hi = float(big.min()), float(big.max())
    return (big - lo) / max(hi - lo, 1e-6)


def clutter_background(size, rng, shapes=120):
    """A BGR ``float32`` background full of edges: smooth colour noise plus random lines,
    rectangles, ellipses and strokes (``shapes`` of them)."""
    w, h = size
    base = np.stack([smooth_noise((h, w), rng, 24) for _ in range(3)], axis=-1)
    img = (60 + 120 * base).astype(np.float32)
    lw = max(1, int(round(min(w, h) / 160)))
    for _ in range(shapes):
        col = tuple(float(c) for c in rng.uniform(20, 235, 3))
        kind = rng.integers(4)
        x, y = int(rng.uniform(0, w)), int(rng.uniform(0, h))
        s = int(rng.uniform(0.03, 0.18) * min(w, h))
        if kind == 0:
            ang = rng.uniform(0, np.pi)
            dx, dy = int(s * np.cos(ang)), int(s * np.sin(ang))
            cv2.line(img, (x - dx, y - dy), (x + dx, y + dy), col, int(rng.integers(1, 3)) * lw, cv2.LINE_AA)
        elif kind == 1:
            cv2.rectangle(img, (x, y), (x + s, y + int(s * rng.uniform(0.3, 1.5))), col,
                          -1 if rng.random() < 0.5 else lw)
        elif kind == 2:
            cv2.ellipse(img, (x, y), (s // 2 + 1, int(s * rng.uniform(0.2, 0.6)) + 1), float(rng.uniform(0, 180)),
                        0, 360, col, -1 if rng.random() < 0.4 else lw, cv2.LINE_AA)
        else:
            pts = np.cumsum(rng.normal(0, s / 3, (6, 2)), axis=0) + (x, y)
            cv2.polylines(img, [pts.astype(np.int32)], False, col, lw, cv2.LINE_AA)
    return img


def motion_blur(img, velocity, border=cv2.BORDER_CONSTANT):
    """Blur along ``velocity (vx, vy)`` (px/frame) with a line kernel of that length (``border``: how
    :func:`cv2.filter2D` extends the image; black by default, as the synthetic clips were made)."""
    length = float(np.hypot(*velocity))
    if length < 1.5:
        return img
    k = int(np.ceil(length)) | 1
    kern = np.zeros((k, k), np.float32)
    c = k // 2
    d = np.asarray(velocity, float) / length * (length / 2)
    cv2.line(kern, (int(round(c - d[0])), int(round(c - d[1]))), (int(round(c + d[0])), int(round(c + d[1]))),
             1.0, 1, cv2.LINE_AA)
    kern /= kern.sum()
    return cv2.filter2D(img, -1, kern, borderType=border)


def lighting(size, t, phase, amplitude=0.25, period=150.0):
    """Multiplicative illumination field at frame ``t``: a global gain that drifts over
    time times a horizontal gradient that sweeps across the frame."""
    w, h = size
    gain = 1.0 + amplitude * np.sin(2 * np.pi * t / period + phase)
    x = np.linspace(0.0, 1.0, w, dtype=np.float32)
    sweep = 1.0 + 0.5 * amplitude * np.cos(2 * np.pi * (x - t / (2 * period)))
    return (gain * sweep)[None, :, None].astype(np.float32)


def add_noise(img, rng, sigma):
    """Sensor noise: additive Gaussian of std ``sigma`` (8-bit units), clipped to uint8."""
    noisy = img + rng.normal(0.0, sigma, img.shape).astype(np.float32)
    return np.clip(noisy, 0, 255).astype(np.uint8)


def write_clip_files(out, rows, columns, meta):
    """Write ``groundtruth.csv`` (header row, one row per frame) and ``meta.json`` into ``out``."""
    write_track_csv(out / "groundtruth.csv", rows, columns)
    with open(out / "meta.json", "w") as f:
        json.dump(meta, f, indent=2)


def _pid_alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass
    return True


def _swap_in(new, out):
    """Put the complete clip folder ``new`` at ``out``: the old folder is renamed aside, ``new``
    renamed into place, what else the old folder held (the user's files) moved over, then the old
    clip removed. ``out`` never holds the new video beside the old ground truth."""
    if not out.exists():
        new.rename(out)
        return
    old = out.with_name(f".{out.name}.old-{os.getpid()}")
    out.rename(old)
    new.rename(out)
    own = _clip_files(old)
    for e in old.iterdir():  # the user's own files; not the old clip's (a plate clip's objects.csv, frames)
        if e.name not in own and not (out / e.name).exists():
            e.rename(out / e.name)
    shutil.rmtree(old)


def _clip_files(folder):
    """The names in a clip folder that are the clip's own: :data:`CLIP_NAMES`, the records of
    :data:`SYNTH_RECORDS` and the video a ``synth perturb`` or ``plate-on-car`` record names (``video``)."""
    own = set(CLIP_NAMES) | set(SYNTH_RECORDS)
    for record in ("perturb.json", "composite.json"):
        try:
            meta = json.loads((folder / record).read_text())
        except (OSError, ValueError):
            continue
        if isinstance(meta, dict) and isinstance(meta.get("video"), str):
            own.add(meta["video"])
    return own


def check_video_size(size):
    """Raise ``ValueError`` unless the clips' MPEG-4 Part 2 video can hold frames of ``size``
    ``(width, height)`` as they are: even sides (the encoder drops an odd last row or column, so
    the video would not match the ground truth) of at most :data:`MAX_SIDE`."""
    w, h = (int(v) for v in size)
    if w % 2 or h % 2:
        raise ValueError(f"frame size {w}x{h}: the clip's MPEG-4 video needs even sides (it would be "
                         f"{w - w % 2}x{h - h % 2} while the ground truth says {w}x{h}); give {w + w % 2}x{h + h % 2}")
    if max(w, h) > MAX_SIDE:
        raise ValueError(f"frame size {w}x{h}: the clip's MPEG-4 video has at most {MAX_SIDE} pixels a side")




def is_synth_clip(folder):
    """Whether ``folder`` holds a clip ``vistrack synth`` wrote: a video beside its record
    (:data:`SYNTH_RECORDS`: ``meta.json`` naming its ``kind`` or ``model``; ``synth perturb``'s
    ``perturb.json`` and ``synth plate-on-car``'s ``composite.json`` naming their ``source``)."""
    folder = Path(folder)
    for record, keys in SYNTH_RECORDS.items():
        video = (folder / "video.mp4").is_file() if record == "meta.json" else any(folder.glob("*.mp4"))
        if not (video and (folder / record).is_file()):
            continue
        try:
            meta = json.loads((folder / record).read_text())
        except (OSError, ValueError):
            continue
        if isinstance(meta, dict) and any(meta.get(k) for k in keys):
            return True
    return False


def _check_clip_out(out):
    """Refuse (``ValueError``) an existing, non-empty ``out`` that is not a clip synth wrote: its
    files (another clip's frames, ground truth) would be mixed with the new clip's."""
    if not out.is_dir() or is_synth_clip(out):
        return
    theirs = sorted(e.name for e in out.iterdir() if not e.name.startswith("."))
    clip = [n for n in theirs if n in CLIP_NAMES or Path(n).suffix.lower() in VIDEO_EXT | IMAGE_EXT]
    if clip:
        raise ValueError(f"{out} holds {', '.join(clip[:3])}{', ...' if len(clip) > 3 else ''}, not a clip vistrack "
                         "synth wrote: the new clip would be mixed with them; give an empty or new folder")


class SuiteNames:
    """The clip names of a suite, ``<kind>-<seed>`` (two digits at least) for ``count`` seeds from
    ``first``: made as they are asked for, so a suite of a billion clips is a range, not a list."""

    def __init__(self, kind, first, count):
        self.kind, self.first, self.count = kind, int(first), int(count)

    def name(self, seed):
        """The folder name of the clip of ``seed``."""
        return f"{self.kind}-{seed:02d}"

    def __len__(self):
        return self.count

    def __iter__(self):
        return (self.name(s) for s in range(self.first, self.first + self.count))

    def __contains__(self, name):
        kind, _, seed = str(name).rpartition("-")
        return (kind == self.kind and seed.isdigit() and self.first <= int(seed) < self.first + self.count
                and name == self.name(int(seed)))


def out_folder(out, clip=True):
    """``synth``'s ``--out`` ready: a clip's folder, its parent made (the clip itself is rendered beside
    it and renamed into place, :func:`atomic_clip`), or with ``clip=False`` a suite's folder, made.
    Returns ``(path, whether a clip is there already)``; a one-line ``ValueError`` where it cannot be."""
    p = Path(out)
    if p.exists() and not p.is_dir():
        raise ValueError(f"--out {p} exists and is not a folder")
    there = clip and p.is_dir() and (p / "video.mp4").exists()
    try:
        (p.parent if clip else p).mkdir(parents=True, exist_ok=True)
    except OSError as e:
        blocked = next((q for q in [p, *p.parents] if q.exists() and not q.is_dir()), None)
        raise ValueError(f"cannot create {p}: " + (f"{blocked} is not a folder" if blocked else e.strerror)) from None
    return p, there


def prepare_suite(out, names):
    """Make folder ``out`` ready for a suite of clips ``names``: refuse (``ValueError``) a folder
    holding anything but clips synth wrote (a suite's folder holds only its clips), and remove
    the clips of an earlier suite that the new one does not write, so that ``out`` holds the new
    suite alone. Returns the names removed."""
    out = Path(out)
    if not out.is_dir():
        return []
    other = [e.name for e in out.iterdir() if not e.name.startswith(".") and not (e.is_dir() and is_synth_clip(e))]
    if other:
        raise ValueError(f"{out} holds {', '.join(sorted(other)[:3])}{', ...' if len(other) > 3 else ''}, which are "
                         "not clips vistrack synth wrote: the clips would be mixed with them; give an empty or new "
                         "folder")
    stale = sorted(e.name for e in out.iterdir() if e.is_dir() and not e.name.startswith(".") and e.name not in names)
    for n in stale:
        shutil.rmtree(out / n)
    return stale


def atomic_clip(make):
    """Decorator of clip makers ``make(out, **kw)``: the clip is rendered into a hidden folder beside
    ``out`` (``.NAME.partial-PID``, which ``eval`` does not take for a clip) and renamed over ``out``
    when it is complete, so an interrupted or failed render leaves the old clip as it was and no
    partial one. Partial folders of dead processes are removed. ``out`` may not hold the current
    folder (``ValueError``). The clip's sizes (frames, frame size, cars, landmarks, clutter blobs) are
    checked first (:func:`~vistrack.data_synth.clip_sizes.check_clip_sizes`: a one-line ``TooLarge``)."""
    sizes = [n for n in ("frames", "size", "cars", "k", "clutter_blobs") if n in inspect.signature(make).parameters]

    @functools.wraps(make)
    def wrapper(out, *args, **kw):
        out = Path(out)
        given = inspect.signature(make).bind(out, *args, **kw)
        given.apply_defaults()
        check_clip_sizes(out.parent, **{n: given.arguments[n] for n in sizes})
        if Path.cwd().resolve().is_relative_to(out.resolve()):
            raise ValueError(f"{out} holds the current folder: give the clip a folder of its own (such as clip/)")
        if out.exists() and not out.is_dir():
            raise ValueError(f"{out} exists and is not a folder")
        if "size" in kw:
            check_video_size(kw["size"])
        _check_clip_out(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        for stale in out.parent.glob(f".{out.name}.partial-*"):
            pid = stale.name.rpartition("-")[2]
            if pid.isdigit() and not _pid_alive(int(pid)):
                shutil.rmtree(stale, ignore_errors=True)
        tmp = out.with_name(f".{out.name}.partial-{os.getpid()}")
        shutil.rmtree(tmp, ignore_errors=True)
        try:
            result = make(tmp, *args, **kw)
            _swap_in(tmp, out)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        return result

    return wrapper
