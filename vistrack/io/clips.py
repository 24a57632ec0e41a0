"""Clip folders: a video plus ground truth and metadata (docs/architecture.md, Conventions).

A synthetic clip folder holds ``video.mp4``, ``groundtruth.csv`` (header row,
one row per frame: ``frame, visible, cx, cy, w, h, angle_deg`` + model columns)
and ``meta.json``. A real clip is a video or an image folder with an OTB-style
``groundtruth_rect.txt`` (``x, y, w, h`` per line). :func:`load_clip` accepts
the folder or the video inside it.
"""

from __future__ import annotations

import csv
import json
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .clip_files import FRAME_FOLDERS, GROUNDTRUTH_FILES
from .outputs import replacing
from .remote import is_url
from .video import VideoError, find_groundtruth, groundtruth_origin, open_video, read_rects

__all__ = ["Clip", "load_clip", "excluded_frames",
           "read_meta", "read_groundtruth_csv", "write_track_csv", "format_value", "excerpt_clip",
           "GroundTruthWarning", "SkippedFoldersWarning", "find_clips", "sequence_name"]


@dataclass
class Clip:
    """An opened clip.

    Attributes
    ----------
    source : VideoSource
    folder : Path
    meta : dict or None
        ``meta.json`` contents (synthetic clips).
    truth : dict of str -> ndarray, or None
        Ground-truth columns (one entry per frame). OTB rectangles become
        ``frame, visible, cx, cy, w, h, x, y``.
    """

    source: object
    folder: Path
    meta: dict | None
    truth: dict | None

    @property
    def remote(self):
        """How a clip given as a URL was read (:class:`~vistrack.io.remote.Remote`: from the server, a
        fresh download or a cached copy checked against the server), or ``None``."""
        return self.source.remote

    @property
    def objects(self):
        """The per-object ground truth (``objects.csv``: a row per frame and object, with ids;
        :mod:`vistrack.scoring.mot`) as columns, or ``None`` when the clip has none."""
        path = self.folder / "objects.csv"
        return read_groundtruth_csv(path) if path.is_file() else None

    @property
    def model_name(self):
        """The model named in ``meta.json`` (a synthetic clip's kind), or ``None``."""
        return (self.meta or {}).get("model")

    def first_box(self):
        """``(x, y, w, h)`` of the first ground-truth frame where the object is visible."""
        t = self.truth
        if t is None:
            raise VideoError(f"{self.folder} has no ground truth (groundtruth.csv or groundtruth_rect.txt)")
        vis = np.flatnonzero(t["visible"] > 0)
        if not len(vis):
            raise VideoError(f"{self.folder}: the object is never visible in the ground truth")
        k = vis[0]
        return t["cx"][k] - t["w"][k] / 2, t["cy"][k] - t["h"][k] / 2, t["w"][k], t["h"][k]


#: track-CSV columns of text (read as ``str`` arrays; every other column is numbers)
TEXT_COLUMNS = ("lost_reason",)


def read_groundtruth_csv(path):
    """Columns of a ``groundtruth.csv`` (or track CSV) as float arrays (:data:`TEXT_COLUMNS`: str; an empty
    number, such as the ``confidence`` of a model without one, is NaN)."""
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            rd = csv.reader(f)
            try:
                header = next(rd)
            except StopIteration:
                raise VideoError(f"{path} is empty") from None
            rows = [r for r in rd if r]
    except UnicodeDecodeError as e:
        raise VideoError(f"{path} is not a text file (byte {e.start} is not UTF-8)") from None
    except csv.Error as e:
        raise VideoError(f"{path} is not a CSV file ({e})") from None
    text = [k for k, h in enumerate(header) if h in TEXT_COLUMNS]
    try:
        if any(len(r) != len(header) for r in rows):
            raise ValueError
        data = np.array([[v if v.strip() else "nan" for k, v in enumerate(r) if k not in text] for r in rows],
                        dtype=float)
    except ValueError:
        raise VideoError(f"{path}: every row needs {len(header)} numbers") from None
    numeric = [h for k, h in enumerate(header) if k not in text]
    out = {h: data[:, k] if len(rows) else np.zeros(0) for k, h in enumerate(numeric)}
    out.update({header[k]: np.array([r[k] for r in rows], dtype=str) for k in text})
    return {h: out[h] for h in header}


def _rects_truth(rects):
    x, y, w, h = rects.T
    ok = (w > 0) & (h > 0) & np.all(np.isfinite(rects), axis=1)
    return {"frame": np.arange(len(rects), dtype=float), "visible": ok.astype(float), "cx": x + w / 2,
            "cy": y + h / 2, "w": w, "h": h, "x": x, "y": y}


def load_clip(path, progress=False):
    """Open a clip folder, a video file (with its folder's ground truth) or an image folder, a camera
    or a live stream (no ground truth); a URL (``http://``, ``s3://``, ...) of a video or clip folder
    is read from the server or from a copy in a local cache checked against the server on every use
    (:func:`vistrack.io.remote.open_url`; ``progress``: a download's progress bar; ``Clip.remote``
    says which)."""
    from .remote import open_remote, open_url
    from .video import is_stream

    if is_stream(path):  # a camera or a live stream: no ground truth
        return Clip(open_video(path), Path.cwd(), None, None)
    if is_url(path) and not str(path).startswith("file://"):
        remote = open_url(str(path), progress=progress)
        if remote.path is None:  # read from the server: a video alone
            return Clip(open_remote(remote), Path.cwd(), None, None)
        source, p = open_remote(remote), remote.path
    else:
        p = Path(str(path)[len("file://"):] if str(path).startswith("file://") else path)
        source = open_video(p)
    folder = p if p.is_dir() else p.parent
    meta = None
    if (folder / "meta.json").is_file():
        meta = read_meta(folder / "meta.json")
    truth = None
    if (folder / "groundtruth.csv").is_file():
        truth = read_groundtruth_csv(folder / "groundtruth.csv")
        missing = {"frame", "visible", "cx", "cy", "w", "h"} - set(truth)
        if missing:
            raise VideoError(f"{folder / 'groundtruth.csv'} lacks columns {', '.join(sorted(missing))}")
        geo = np.abs(np.nan_to_num(np.column_stack([truth[c] for c in ("cx", "cy", "w", "h")]), posinf=np.inf,
                                   neginf=np.inf))
        if geo.size and np.any(geo > 1e6):
            k = int(np.flatnonzero(np.any(geo > 1e6, axis=1))[0])
            raise VideoError(f"{folder / 'groundtruth.csv'}, line {k + 2}: cx, cy, w, h must be pixel coordinates "
                             "and sizes (at most 1e+06), or NaN where the object is not in view")
    elif find_groundtruth(p) is not None:
        gt = find_groundtruth(p)
        truth = _rects_truth(read_rects(gt, origin=groundtruth_origin(gt)))
        flagged = excluded_frames(folder, len(truth["cx"]))
        truth["visible"][flagged] = 0.0  # not scored, as the toolkits do; the box stays for reference
        truth["excluded"] = flagged
    if truth is not None and source.frame_count and len(truth["cx"]) != source.frame_count:
        k, n = len(truth["cx"]), source.frame_count
        warnings.warn(f"{folder}: the ground truth has {k} rows for {n} frames; "
                      + ("frames past its end are not scored" if k < n else "its extra rows are ignored"),
                      GroundTruthWarning, stacklevel=2)
    return Clip(source, folder, meta, truth)


#: per-frame flags of frames the datasets' toolkits leave out of the scores: LaSOT's full occlusion
#: and out of view (one line of comma-separated 0/1), GOT-10k's absence (a 0/1 per line)
EXCLUSION_FILES = ("full_occlusion.txt", "out_of_view.txt", "absence.label")


def excluded_frames(folder, n):
    """``(n,)`` bool: frames flagged fully occluded or out of view (LaSOT) or absent (GOT-10k) in
    ``folder`` (``n``: the ground truth's rows); a flag file that is not 0/1 values is a :class:`VideoError`
    naming it, one of another length a :class:`GroundTruthWarning` with both counts (the frames past its
    end are not flagged; its extra flags are ignored)."""
    out = np.zeros(n, bool)
    for name in EXCLUSION_FILES:
        f = Path(folder) / name
        if not f.is_file():
            continue
        text = f.read_text(errors="replace").replace(",", " ").split()
        if any(v not in ("0", "1") for v in text):
            raise VideoError(f"{f}: expected 0/1 flags, one per frame")
        if len(text) != n:
            warnings.warn(f"{f} has {len(text)} flags for the {n} rows of the ground truth; "
                          + ("the frames past its end are taken as not flagged" if len(text) < n
                             else "its extra flags are ignored"), GroundTruthWarning, stacklevel=3)
        flags = np.array([v == "1" for v in text], bool)[:n]
        out[: len(flags)] |= flags
    return out


def read_meta(path):
    """A clip's ``meta.json`` as a dict; a :class:`VideoError` naming the file for one that is not
    text, not JSON, or not a JSON object (``{...}``), or whose ``model`` is not a name."""
    try:
        meta = json.loads(Path(path).read_text(encoding="utf-8-sig"))
    except UnicodeDecodeError as e:
        raise VideoError(f"{path} is not a text file (byte {e.start} is not UTF-8)") from None
    except (json.JSONDecodeError, RecursionError) as e:
        raise VideoError(f"{path} is not valid JSON: {e}") from None
    if not isinstance(meta, dict):
        raise VideoError(f"{path} holds a JSON {type(meta).__name__}, not an object ({{\"model\": ..., ...}})")
    if "model" in meta and not isinstance(meta["model"], str):
        raise VideoError(f"{path}: \"model\" must be a model name, got {json.dumps(meta['model'])[:40]}")
    return meta


class GroundTruthWarning(UserWarning):
    """The ground truth and the video disagree (e.g. in length)."""


class SkippedFoldersWarning(UserWarning):
    """Folders of a dataset root that hold no clip were left out."""


def write_track_csv(path, rows, columns=None):
    """Write track rows (dicts) with a header; ``columns`` fixes the order (default: first row's keys)."""
    columns = columns or (list(rows[0]) if rows else [])
    with open(path, "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(columns)
        for r in rows:
            wr.writerow([format_value(r.get(c, "")) for c in columns])


_FLOATS = (float, np.float64, np.float32)


def format_value(v):
    """A track-CSV cell: integers and flags as integers, numbers with 3 decimals, text as is; a number
    that is not finite (a plate frame's geometry where no plate is in view) an empty cell, which
    :func:`read_groundtruth_csv` reads back as NaN."""
    if type(v) in _FLOATS:  # the common case first: a track row is mostly floats
        return f"{float(v):.3f}" if math.isfinite(v) else ""
    if isinstance(v, (bool, np.bool_)):
        return str(int(v))
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, str):
        return v
    return f"{float(v):.3f}" if math.isfinite(float(v)) else ""


def excerpt_clip(src, dst, frames):
    """Write the first ``frames`` frames of the clip ``src`` (any layout :func:`load_clip`
    opens, with box ground truth) into folder ``dst``: ``img/`` of lossless PNGs and a 0-based
    ``groundtruth.txt`` (``x,y,w,h``, ``0,0,0,0`` where the object is absent: the GOT-10k
    layout). Returns ``dst``."""
    import cv2

    clip = load_clip(src)
    if clip.truth is None or "w" not in clip.truth:
        raise VideoError(f"{src}: no box ground truth to excerpt")
    dst = Path(dst)
    (dst / "img").mkdir(parents=True, exist_ok=True)
    n = 0
    for i, frame in clip.source:
        if i >= frames:
            break
        if not cv2.imwrite(str(dst / "img" / f"{i + 1:08d}.png"), frame):
            raise VideoError(f"cannot write {dst / 'img'}")
        n = i + 1
    written = {f"{k + 1:08d}.png" for k in range(n)}
    for p in (dst / "img").iterdir():  # an earlier, longer excerpt's frames
        if p.name not in written and p.suffix.lower() == ".png":
            p.unlink()
    t = clip.truth
    with replacing(dst / "groundtruth.txt", "ground truth") as tmp, open(tmp, "w") as f:
        for k in range(min(n, len(t["cx"]))):
            box = (t["cx"][k] - t["w"][k] / 2, t["cy"][k] - t["h"][k] / 2, t["w"][k], t["h"][k])
            f.write(",".join(f"{v:.2f}" for v in (box if t["visible"][k] > 0 else (0, 0, 0, 0))) + "\n")
    return dst


# -- clip folders from the user's paths (eval, run) ------------------------------------------
def _is_clip(p):
    """A clip folder: a synthetic clip, or images (``img/``, VOT's ``color/``, or in the folder) or a
    video with box ground truth of a known layout (OTB, VOT, GOT-10k, LaSOT)."""
    return ((p / "video.mp4").is_file() or any((p / f).is_dir() for f in FRAME_FOLDERS)
            or any((p / g).is_file() for g in (*GROUNDTRUTH_FILES, "groundtruth.csv")))


def _dataset_clips(p):
    """The clip folders of a dataset root ``p``: a VOT workspace (``sequences/``), a GOT-10k split or
    VOT's ``sequences`` (``list.txt`` names them, in its order), a folder of clip folders, or LaSOT's
    ``root/category/sequence``; ``[]`` when there is none."""
    if (p / "sequences").is_dir() and not _is_clip(p):
        p = p / "sequences"
    if (p / "list.txt").is_file():
        names = [n.strip() for n in (p / "list.txt").read_text(errors="replace").splitlines() if n.strip()]
        missing = [n for n in names if not (p / n).is_dir()]
        if missing:
            raise VideoError(f"{p / 'list.txt'} names sequences that are not folders in {p}: "
                             + ", ".join(missing[:5]) + (" ..." if len(missing) > 5 else ""))
        return [p / n for n in names]
    # hidden folders are not clips: synth renders into .NAME.partial-PID before renaming it
    subs = sorted(q for q in p.iterdir() if q.is_dir() and not q.name.startswith("."))
    clips = [q for q in subs if _is_clip(q)]
    if not clips:  # LaSOT: root/category/sequence
        subs = [r for q in subs for r in sorted(q.iterdir()) if r.is_dir() and not r.name.startswith(".")]
        clips = [r for r in subs if _is_clip(r)]
    skipped = [q for q in subs if q not in clips]
    if clips and skipped:
        names = ", ".join(str(q.relative_to(p)) for q in skipped[:5]) + (", ..." if len(skipped) > 5 else "")
        warnings.warn(f"{p}: {len(skipped)} folder(s) hold no clip (no video.mp4, img/ or color/ frames and no "
                      f"ground truth) and were left out: {names}", SkippedFoldersWarning, stacklevel=3)
    return clips


def find_clips(paths):
    """Clip folders from clip folders, videos or dataset roots (folders of clip folders; a LaSOT root
    with category folders; a GOT-10k split or a VOT workspace, in its ``list.txt`` order).

    Raises ``VideoError`` for a missing path, an empty directory, or a clip
    without ground truth (eval needs it; ``run`` does not).
    """
    clips = []
    for raw in paths:
        if is_url(raw):  # one clip folder, fetched where it is read (vistrack.io.remote)
            clips.append(str(raw))
            continue
        p = Path(raw)
        if not p.exists():
            raise VideoError(f"{p} does not exist")
        if p.is_file() or _is_clip(p):
            clips.append(p)
            continue
        sub = _dataset_clips(p)
        if not sub:
            raise VideoError(f"{p} holds no clips (folders with a video or images and box ground truth: OTB, VOT, "
                             "GOT-10k, LaSOT or vistrack's own layout)")
        clips.extend(sub)
    for c in clips:
        truth = load_clip(c).truth
        if truth is None:
            raise VideoError(f"{c} has no ground truth (groundtruth.csv or groundtruth_rect.txt): "
                             "eval needs ground truth; `vistrack run` does not")
        if not np.any(truth["visible"] > 0):
            raise VideoError(f"the ground truth of {c} has no frame with the object in view (every row empty, NaN "
                             "or 0,0,0,0): eval starts each run from the first box in view")
    return clips


def sequence_name(clip):
    """A clip's sequence name: its folder's (a video's parent folder's; a URL's last part); result files
    are named after it."""
    if is_url(clip):
        return str(clip).rstrip("/").rsplit("/", 1)[-1]
    p = Path(clip)
    return p.parent.name if p.is_file() else p.name

