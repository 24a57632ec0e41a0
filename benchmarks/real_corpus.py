"""The real clips with ground truth as a benchmark corpus: clips, start boxes as users give them,
OTB's spatial-robustness starts, trackers run on decoded frames, scores (issues 43 and 44).

Shared by ``bench_real.py`` (the table of record) and ``tune_box.py`` (defaults chosen by
cross-validation). Nothing here is part of vistrack.

Clips
    every folder under ``../shared/data/real`` holding ``groundtruth_rect.txt`` (globbed, so a clip
    added later is included). Frames are decoded once into ``~/.cache/vistrack/frames`` (``.npy``,
    keyed by the video's size and modification time) and memory-mapped from there.
Truth
    the ground truth read as ``vistrack eval`` reads it (:func:`vistrack.io.video.read_rects` with
    the layout's origin), frames without a box are not scored.
The user's start box
    the first line of the ground-truth file as written, in whole pixels (rounded), passed unchanged
    to every tracker, as a user pasting it into ``vistrack run --init`` would give it (for OTB's
    1-based files one pixel off the 0-based truth; the same box for every tracker).
Robustness starts (OTB's SRE)
    that box shifted by 10 % of its width and height in the 8 directions, and scaled about its centre
    by 0.8, 0.9, 1.1 and 1.2 (12 starts, whole pixels).
"""

from __future__ import annotations

import hashlib
import json
import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from vistrack.io.video import find_groundtruth, groundtruth_origin, open_video, read_rects
from vistrack.scoring.metrics import box_scores, iou

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "real"
NANOTRACK = ROOT.parent / "shared" / "data" / "baselines" / "nanotrack"
FRAME_CACHE = Path(os.environ.get("VISTRACK_FRAME_CACHE", Path.home() / ".cache" / "vistrack" / "frames"))
#: finished runs' scores (JSON lines keyed by the code's digest, clip, tracker, start, seed and options)
SCORE_CACHE = Path.home() / ".cache" / "vistrack" / "corpus_runs.jsonl"
#: OTB's spatial-robustness starts: shifts (share of w, h) and scales about the centre
SRE_SHIFTS = [(dx, dy) for dx in (-0.1, 0.0, 0.1) for dy in (-0.1, 0.0, 0.1) if (dx, dy) != (0.0, 0.0)]
SRE_SCALES = (0.8, 0.9, 1.1, 1.2)
#: OpenCV's trackers by name (KCF and CSRT need opencv-contrib-python-headless; Nano needs the weights)
OPENCV = ("MIL", "KCF", "CSRT", "Nano")
#: NanoTrack v3 with its authors' tracker logic (vistrack.baselines.nanotrack), on the weights vistrack ships
NANOTRACK_V3 = "NanoV3"


@dataclass
class Clip:
    """A clip of the corpus: its folder, truth ``(T, 4)`` 0-based and the user's start box."""

    folder: Path
    truth: np.ndarray
    user_box: tuple
    video: Path

    @property
    def name(self):
        return self.folder.name

    def frames(self):
        """The decoded frames ``(T, H, W, 3) uint8`` (memory-mapped from the cache; decoded once)."""
        return cached_frames(self.video, len(self.truth))


def find_clips(data=DATA, names=None):
    """The corpus: every folder under ``data`` with ``groundtruth_rect.txt`` (sorted), or those ``names``."""
    folders = sorted(p.parent for p in Path(data).glob("*/groundtruth_rect.txt"))
    if names:
        by = {p.name: p for p in folders}
        missing = [n for n in names if n not in by]
        if missing:
            raise SystemExit(f"not found under {data} (or without groundtruth_rect.txt): {', '.join(missing)}")
        folders = [by[n] for n in names]
    return [load_clip(f) for f in folders]


def load_clip(folder):
    folder = Path(folder)
    gt_path = find_groundtruth(folder)
    truth = read_rects(gt_path, origin=groundtruth_origin(gt_path))
    videos = sorted(p for p in folder.iterdir() if p.suffix.lower() in (".mp4", ".avi", ".mkv", ".mov"))
    video = videos[0] if videos else folder
    return Clip(folder, truth, user_box(gt_path), video)


def user_box(gt_path):
    """The first line of a ground-truth file as written, in whole pixels: ``(x, y, w, h)`` ints."""
    for line in Path(gt_path).read_text().splitlines():
        vals = [v for v in line.replace("\t", ",").replace(" ", ",").split(",") if v.strip()]
        if vals:
            v = [float(x) for x in vals]
            if len(v) == 8:  # a VOT polygon: its bounding box
                xs, ys = v[0::2], v[1::2]
                v = [min(xs), min(ys), max(xs) - min(xs), max(ys) - min(ys)]
            return tuple(int(round(x)) for x in v[:4])
    raise ValueError(f"{gt_path} has no box")


def sre_starts(box):
    """OTB's 12 spatial-robustness starts of ``box`` ``(x, y, w, h)`` in whole pixels."""
    x, y, w, h = box
    out = [(int(round(x + dx * w)), int(round(y + dy * h)), w, h) for dx, dy in SRE_SHIFTS]
    cx, cy = x + w / 2, y + h / 2
    for s in SRE_SCALES:
        sw, sh = max(1, int(round(w * s))), max(1, int(round(h * s)))
        out.append((int(round(cx - sw / 2)), int(round(cy - sh / 2)), sw, sh))
    return out


def cached_frames(video, n):
    """The first ``n`` frames of ``video`` as one ``(n, H, W, 3) uint8`` array, decoded once into the cache."""
    st = Path(video).stat()
    key = hashlib.sha1(f"{Path(video).resolve()}|{st.st_size}|{st.st_mtime_ns}|{n}".encode()).hexdigest()[:12]
    path = FRAME_CACHE / f"{Path(video).stem}-{key}.npy"
    if not path.is_file():
        frames = []
        for _, f in open_video(video):
            frames.append(f if f.ndim == 3 else cv2.cvtColor(f, cv2.COLOR_GRAY2BGR))
            if len(frames) == n:
                break
        FRAME_CACHE.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp.npy")
        np.save(tmp, np.stack(frames))
        os.replace(tmp, path)
    return np.load(path, mmap_mode="r")


def decode_seconds(video, n):
    """Seconds to decode the first ``n`` frames of ``video`` (vistrack's reader, one pass)."""
    t0 = time.perf_counter()
    k = 0
    for _ in open_video(video):
        k += 1
        if k == n:
            break
    return time.perf_counter() - t0


# -- trackers -------------------------------------------------------------------------------------------
def opencv_tracker(name):
    """A new ``cv2.Tracker<name>`` (``Nano`` with the weights in ``../shared/data/baselines``), or ``None``."""
    if name == "Nano":
        if not (NANOTRACK / "nanotrack_backbone_sim.onnx").is_file() or not hasattr(cv2, "TrackerNano"):
            return None
        p = cv2.TrackerNano_Params()
        p.backbone = str(NANOTRACK / "nanotrack_backbone_sim.onnx")
        p.neckhead = str(NANOTRACK / "nanotrack_head_sim.onnx")
        return cv2.TrackerNano_create(p)
    for ns in (cv2, getattr(cv2, "legacy", None)):
        if ns is not None and hasattr(ns, f"Tracker{name}_create"):
            return getattr(ns, f"Tracker{name}_create")()
    cls = getattr(cv2, f"Tracker{name}", None)
    return cls.create() if cls is not None and hasattr(cls, "create") else None


@dataclass
class Run:
    """One tracker's run on one clip from one start: boxes ``(T, 4)``, whether each frame was reported
    visible ``(T,)``, its confidence ``(T,)`` (NaN where the tracker gives none), tracking seconds; for
    vistrack's box model, the confidence's cues ``(T, F)`` (:mod:`vistrack.models.box.confidence`; NaN on
    the first frame), whether each frame was a re-detection ``(T,)`` and its ``lost_reason`` ``(T,)``; probed
    (``vistrack-probe``), a whole-frame search's ``K`` candidates on every frame after the first: their
    cues ``(T, K, len(SEEN))`` and boxes ``(T, K, 4)``."""

    boxes: np.ndarray
    visible: np.ndarray
    confidence: np.ndarray
    seconds: float
    features: np.ndarray | None = None
    redetected: np.ndarray | None = None
    reasons: np.ndarray | None = None
    candidates: np.ndarray | None = None
    candidate_boxes: np.ndarray | None = None


def run_vistrack(frames, start, seed, options=None, n_frames=None, probe=False):
    """vistrack's default box tracker (``vistrack.Tracker(seed=seed, **options)``) from ``start``; ``probe``:
    after every frame, a whole-frame search's candidates (``Box.search_whole``) and their cues, which change
    nothing the tracking reads."""
    import vistrack
    from vistrack.models.box.confidence import FEATURES, SEEN

    n = len(frames) if n_frames is None else n_frames
    t = vistrack.Tracker(seed=seed, **(options or {}))
    boxes, vis, conf = np.zeros((n, 4)), np.ones(n, bool), np.full(n, np.nan)
    feats, found, reasons = np.full((n, len(FEATURES)), np.nan), np.zeros(n, bool), np.full(n, "", dtype=object)
    t0 = time.perf_counter()
    t.init(np.asarray(frames[0]), start)
    boxes[0] = t.box_estimate
    cues = getattr(t.model, "conf", None)  # the box model's confidence cues
    k = 2 * t.model.search_peaks if probe else 0  # at most two scales
    cand, cand_boxes = np.full((n, k, len(SEEN)), np.nan), np.full((n, k, 4), np.nan)
    for i in range(1, n):
        ok, _ = t.update(np.asarray(frames[i]))
        for j, (obs, pose) in enumerate(t.model.search_whole(np.asarray(frames[i])) if probe else []):
            cand[i, j] = cues.candidate_cues(t.model, obs, pose)
            cand_boxes[i, j] = t.model.box(np.concatenate([pose, pose]))[0]
        boxes[i], vis[i] = t.box_estimate, ok
        c = getattr(t, "confidence", None)
        if c is not None:
            conf[i] = c
        if cues is not None and cues.features is not None:
            feats[i] = cues.features
        found[i], reasons[i] = t.result.redetected, t.lost_reason
    return Run(boxes, vis, conf, time.perf_counter() - t0, feats if cues is not None else None, found,
               reasons.astype(str), cand if probe else None, cand_boxes if probe else None)


def run_nanotrack_v3(frames, start, n_frames=None):
    """NanoTrack v3 with its authors' tracker logic (:class:`vistrack.baselines.nanotrack.NanoTrackV3`) from
    ``start``: deterministic, always reports the object."""
    from vistrack.baselines.nanotrack import NanoTrackV3

    n = len(frames) if n_frames is None else n_frames
    tr = NanoTrackV3()
    boxes = np.zeros((n, 4))
    t0 = time.perf_counter()
    tr.init(np.asarray(frames[0]), tuple(int(v) for v in start))
    boxes[0] = start
    for i in range(1, n):
        boxes[i] = tr.update(np.asarray(frames[i]))[1]
    return Run(boxes, np.ones(n, bool), np.full(n, np.nan), time.perf_counter() - t0)


def run_opencv(frames, start, name, n_frames=None):
    """OpenCV's tracker ``name`` from ``start``; a failed ``update`` holds its last box and reports not visible."""
    n = len(frames) if n_frames is None else n_frames
    tr = opencv_tracker(name)
    boxes, vis = np.zeros((n, 4)), np.ones(n, bool)
    t0 = time.perf_counter()
    tr.init(np.asarray(frames[0]), tuple(int(v) for v in start))
    boxes[0] = last = start
    for i in range(1, n):
        ok, r = tr.update(np.asarray(frames[i]))
        last = tuple(r) if ok else last
        boxes[i], vis[i] = last, bool(ok)
    return Run(boxes, vis, np.full(n, np.nan), time.perf_counter() - t0)


# -- the jobs, in worker processes --------------------------------------------------------------------
def _job(args):
    """One run: ``(clip folder, tracker, start, seed, options)`` -> (scores, run)."""
    folder, tracker, start, seed, options = args
    clip = load_clip(folder)
    frames = clip.frames()
    cv2.setNumThreads(1)
    if tracker in ("vistrack", "vistrack-probe"):
        run = run_vistrack(frames, start, seed, options, probe=tracker == "vistrack-probe")
    elif tracker == NANOTRACK_V3:
        run = run_nanotrack_v3(frames, start)
    else:
        run = run_opencv(frames, start, tracker)
    return box_scores(run.boxes, clip.truth[: len(run.boxes)]), run


def iter_jobs(jobs, workers=2):
    """``(scores, Run)`` of each of ``jobs`` (see :func:`_job`), in order, as each finishes, over ``workers``
    processes (spawned, not forked: a fork after OpenCV's DNN or thread pools started, NanoTrack made
    here, can hang)."""
    if workers <= 1:
        yield from map(_job, jobs)
        return
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as ex:
        yield from ex.map(_job, jobs, chunksize=1)


def run_jobs(jobs, workers=2, progress=None):
    """``[(scores, Run)]`` of ``jobs`` (see :func:`_job`), in order, over ``workers`` processes;
    ``progress(result)`` after each."""
    out = []
    for r in iter_jobs(jobs, workers):
        out.append(r)
        if progress:
            progress(r)
    return out


def code_digest(root=ROOT / "vistrack"):
    """SHA-1 of every ``.py`` file under ``root`` (names and contents) and of OpenCV's version: a cached run
    is reused only for the same code."""
    h = hashlib.sha1(cv2.__version__.encode())
    for p in sorted(Path(root).rglob("*.py")):
        h.update(str(p.relative_to(root)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


def cached_scores(jobs, *, cache=SCORE_CACHE, workers=2, desc="runs"):
    """The scores ``(auc, precision, error)`` of each of ``jobs`` (see :func:`_job`), in order: read from
    ``cache`` where the same code ran the same job before, the rest run (``workers`` processes) and added."""
    from tqdm import tqdm

    digest = code_digest()
    keys = [json.dumps([digest, Path(f).name, t, [int(v) for v in st], s if t == "vistrack" else 0, o or {}],
                       sort_keys=True) for f, t, st, s, o in jobs]
    done = {}
    if cache and Path(cache).is_file():
        for line in Path(cache).read_text().splitlines():
            try:
                rec = json.loads(line)
                done[rec["key"]] = rec["scores"]
            except (json.JSONDecodeError, KeyError):
                continue
    todo = {k: j for k, j in zip(keys, jobs) if k not in done}
    if todo:
        if cache:
            Path(cache).parent.mkdir(parents=True, exist_ok=True)
        bar = tqdm(total=len(todo), desc=desc, unit="run", file=sys.stderr)
        pending = iter(todo)
        with open(cache, "a") if cache else open(os.devnull, "w") as fh:
            def record(result):  # each run kept as it ends: an interrupted table resumes where it stopped
                k = next(pending)
                done[k] = [float(v) for v in result[0]]
                fh.write(json.dumps({"key": k, "scores": done[k]}) + "\n")
                fh.flush()
                bar.update()

            run_jobs(list(todo.values()), workers, progress=record)
        bar.close()
    return [done[k] for k in keys]


def lost_runs(boxes, truth, min_len=5):
    """Frames ``(T,) bool`` where ``boxes`` have IoU 0 with a present true box in runs of at least ``min_len``."""
    present = (truth[:, 2] > 0) & (truth[:, 3] > 0)
    zero = present & (iou(boxes, truth) <= 0)
    out = np.zeros(len(zero), bool)
    i = 0
    while i < len(zero):
        if zero[i]:
            j = i
            while j < len(zero) and zero[j]:
                j += 1
            if j - i >= min_len:
                out[i:j] = True
            i = j
        else:
            i += 1
    return out
