"""Batch evaluation: clip × algorithm × N × run -> tasks -> results (DESIGN.md, evaluation protocol).

Every task tracks one clip once and writes its own result file
``tasks/<clip>__<algo>__N<n>__r<run>.json`` (written to a temporary name and
renamed, so a file that exists is complete). Finished tasks are skipped on
``resume``; a worker that dies loses only its own task. Run ``r`` on clip
``c`` draws from ``SeedSequence(seed).spawn(clips)[c].spawn(runs)[r]`` (the
same stream for every algorithm and N: common random numbers), so results do
not depend on the number of workers or the order in which tasks run.

Boxes are ``(cx ± w/2, cy ± h/2)`` with ``cx, cy`` the pose centre, as in
groundtruth.csv. Per frame a task records the centre error, whether the tracker is lost
(centre error > 50 px at 240-px width, scaled — thesis §3.2.5), the IoU of the
estimated box with the true box, ESS and ms. :func:`summarize` turns the task
files into per clip × algo × N summaries (mean error over frames not lost,
P(lost) per frame and overall, success AUC over IoU thresholds 0..1,
precision at 20 px, frames/s, mean ESS).
"""

from __future__ import annotations

import json
import os
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .builders import build_model
from .clips import load_clip
from .filters import ALGORITHMS, make_filter
from .metrics import IOU_THRESHOLDS, center_error, iou, lost_frames, summarize_runs
from .models.registry import get_model_spec

#: centre-error thresholds (px) of the precision plot (OTB)
PRECISION_THRESHOLDS = np.arange(0, 51)
from .runtime import keep_freed_memory
from .tracking import track
from .video import VideoError

__all__ = ["EvalConfig", "find_clips", "task_list", "entry_tasks", "entries_config", "run_task", "execute", "summarize", "pooled_summary",
           "OPENCV_TRACKERS", "check_algos", "task_fingerprint", "task_done", "stale_tasks", "write_task_result", "write_atomic", "OutLocked", "lock_out"]

#: OpenCV trackers by name -> constructor attribute (contrib ones may be missing)
OPENCV_TRACKERS = {"opencv-mil": "TrackerMIL_create", "opencv-kcf": "TrackerKCF_create",
                   "opencv-csrt": "TrackerCSRT_create"}


@dataclass
class EvalConfig:
    clips: list
    algos: list = field(default_factory=lambda: ["lis", "bootstrap"])
    particles: list = field(default_factory=lambda: [100, 750])
    runs: int = 20
    seed: int = 0
    model: str = "contour"
    #: explicit (algo, N) pairs instead of the algos × particles grid
    entries: list | None = None


def check_algos(algos):
    """Raise ``ValueError`` for unknown algorithms or OpenCV trackers this OpenCV lacks."""
    import cv2

    for a in algos:
        if a in OPENCV_TRACKERS:
            if not hasattr(cv2, OPENCV_TRACKERS[a]) and not hasattr(getattr(cv2, "legacy", None), OPENCV_TRACKERS[a]):
                raise ValueError(f"{a} is not in this OpenCV build ({cv2.__version__}); "
                                 "KCF and CSRT need opencv-contrib-python")
        elif a not in ALGORITHMS:
            known = sorted(set(ALGORITHMS) | set(OPENCV_TRACKERS))
            raise ValueError(f"unknown algorithm {a!r}; choose from {', '.join(known)}")


def _is_clip(p):
    return (p / "video.mp4").is_file() or (p / "img").is_dir() or (p / "groundtruth_rect.txt").is_file()


def find_clips(paths):
    """Clip folders from clip folders, videos or directories of clip folders.

    Raises ``VideoError`` for a missing path, an empty directory, or a clip
    without ground truth (eval needs it; ``run`` does not).
    """
    clips = []
    for raw in paths:
        p = Path(raw)
        if not p.exists():
            raise VideoError(f"{p} does not exist")
        if p.is_file() or _is_clip(p):
            clips.append(p)
            continue
        sub = sorted(q for q in p.iterdir() if q.is_dir() and _is_clip(q))
        if not sub:
            raise VideoError(f"{p} holds no clips (folders with video.mp4 or img/ and ground truth)")
        clips.extend(sub)
    for c in clips:
        if load_clip(c).truth is None:
            raise VideoError(f"{c} has no ground truth (groundtruth.csv or groundtruth_rect.txt): "
                             "eval needs ground truth; `vistrack run` does not")
    return clips


def _name(clip):
    p = Path(clip)
    return (p.parent.name if p.is_file() else p.name).replace("__", "_")


def task_list(cfg, clips):
    """All tasks as dicts ``{clip, clip_index, algo, particles, run, seed_seq, name}``."""
    streams = np.random.SeedSequence(cfg.seed).spawn(len(clips))
    tasks = []
    for ci, clip in enumerate(clips):
        seqs = streams[ci].spawn(cfg.runs)
        pairs = cfg.entries or [(a, n) for a in cfg.algos
                                 for n in ([1] if a in OPENCV_TRACKERS else cfg.particles)]
        for algo, n in pairs:
            for r in range(cfg.runs):
                if algo in OPENCV_TRACKERS and r > 0:
                    continue  # deterministic: one run
                tasks.append({"clip": str(clip), "clip_index": ci, "algo": algo, "particles": int(n), "run": r,
                              "seed_seq": seqs[r], "model": cfg.model,
                              "name": f"{ci:03d}_{_name(clip)}__{algo}__N{n}__r{r}"})
    return tasks


def entry_tasks(cfg, model):
    """The tasks of an experiment config with ``clips``, ``entries`` (algo, N), ``runs`` and
    ``seed`` (the contour and plate reproductions) on ``model``; lost by the thesis's rules
    (the contour's 50 px at 240-px width, the plate's vertex rule)."""
    ev = EvalConfig(clips=list(cfg.clips), entries=[tuple(e) for e in cfg.entries], runs=cfg.runs, seed=cfg.seed,
                    model=model)
    tasks = task_list(ev, list(cfg.clips))
    for t in tasks:
        t["lost_rule"] = "thesis"
    return tasks


def entries_config(cfg):
    """Such a config as a JSON-ready dict."""
    from dataclasses import asdict

    d = asdict(cfg)
    d["clips"] = [str(c) for c in cfg.clips]
    d["entries"] = [list(e) for e in cfg.entries]
    return d


def _by_index(values, index):
    """Rows placed at their frame ``index``: frames that failed to decode (absent indices) are
    NaN, so they count as lost rather than shifting every later frame against the truth."""
    values, index = np.asarray(values, float), np.asarray(index, int)
    if np.array_equal(index, np.arange(len(index))):
        return values
    out = np.full((index.max() + 1,) + values.shape[1:], np.nan)
    out[index] = values
    return out


def _truth_boxes(t):
    return np.stack([t["cx"] - t["w"] / 2, t["cy"] - t["h"] / 2, t["w"], t["h"]], axis=1)


def _track_opencv(algo, clip, frames):
    import cv2

    ctor = getattr(cv2, OPENCV_TRACKERS[algo], None) or getattr(cv2.legacy, OPENCV_TRACKERS[algo])
    tracker = ctor()
    x, y, w, h = clip.first_box()
    boxes, ms, index = [], [], []
    for k, (i, frame) in enumerate(frames):
        index.append(i)
        t0 = time.perf_counter()
        if k == 0:
            tracker.init(frame, (int(round(x)), int(round(y)), int(round(w)), int(round(h))))
            box = (x, y, w, h)
        else:
            ok, b = tracker.update(frame)
            box = tuple(float(v) for v in b) if ok else (np.nan,) * 4
        ms.append((time.perf_counter() - t0) * 1e3)
        boxes.append(box)
    return _by_index(np.array(boxes, float), index), np.array(ms), np.full(max(index) + 1, np.nan)


def prepare_worker():
    """Prepare an engine worker: one worker per core, so keep OpenCV from starting threads of its
    own; and let ``malloc`` reuse freed memory (:func:`keep_freed_memory`)."""
    import cv2

    cv2.setNumThreads(1)
    keep_freed_memory()


def run_task(task, out_dir):
    """Track one clip once; write ``out_dir/tasks/<name>.json``; return its path."""
    prepare_worker()
    out = Path(out_dir) / "tasks" / f"{task['name']}.json"
    clip = load_clip(task["clip"])
    frames = list(clip.source)
    algo, n = task["algo"], task["particles"]
    # eval: the object's own size (the plate's vertex rule for plates); reproduce: the thesis's
    rule = "centre" if task.get("lost_rule") == "thesis" else "size"
    reported, vertices, aspect = [], [], None
    if algo in OPENCV_TRACKERS:
        boxes, ms, ess = _track_opencv(algo, clip, frames)
    else:
        spec = get_model_spec(task["model"])
        model = build_model(task["model"], clip, init_gt="")
        filt = make_filter(algo, model)
        rng = np.random.default_rng(task["seed_seq"])
        est, ms, ess, index = [], [], [], []
        for res in track(frames, filt, n, rng):
            index.append(res.index)
            est.append(res.estimate)
            ms.append(res.ms)
            ess.append(res.ess)
            if spec.lost_rule == "plate":  # the maps are overwritten by the next frame: report now
                reported.append(bool(model.visible(res.maps, res.estimate)))
                vertices.append(model.vertices(res.estimate)[0])
        est = np.array(est)
        wh = model.box(est)[:, 2:]
        # boxes centred on the pose centre, as groundtruth.csv's (cx, cy, w, h)
        boxes = _by_index(np.concatenate([est[:, :2] - wh / 2, wh], axis=1), index)
        ms, ess = np.array(ms), _by_index(np.array(ess), index)
        if spec.lost_rule == "plate":
            rule, aspect = "plate", model.layout.aspect
    t = clip.truth
    m = min(len(boxes), len(t["cx"]))
    truth = _truth_boxes(t)[:m]
    boxes = boxes[:m]
    err = center_error(boxes[:, 0] + boxes[:, 2] / 2, boxes[:, 1] + boxes[:, 3] / 2,
                       truth[:, 0] + truth[:, 2] / 2, truth[:, 1] + truth[:, 3] / 2)
    err = np.where(np.isfinite(err), err, np.inf)
    visible = np.asarray(t["visible"][:m]) > 0
    result = {
        "clip": task["clip"], "algo": algo, "particles": n, "run": task["run"],
        "frames": int(m), "visible": visible.astype(int).tolist(),
        "error": [float(e) if np.isfinite(e) else None for e in err],
        "lost": lost_frames(rule, err, clip.source.size[0], truth=t, reported=reported[:m], vertices=vertices[:m],
                            aspect=aspect).astype(int).tolist(),
        "iou": [float(v) for v in np.nan_to_num(iou(boxes, truth), nan=0.0)],
        "ms": [float(v) for v in ms[:m]],
        "ess": [None if not np.isfinite(v) else float(v) for v in ess[:m]],
    }
    return write_task_result(out, result, task)


def _clip_signature(clip):
    """Name, size and modification time of the files of a clip (its folder, or a video file's
    folder): a changed video or ground truth changes the signature."""
    p = Path(clip)
    folder = p if p.is_dir() else p.parent
    out = []
    try:
        for e in sorted(os.scandir(folder), key=lambda e: e.name):
            if e.is_file():
                st = e.stat()
                out.append((e.name, st.st_size, st.st_mtime_ns))
            elif e.is_dir():
                out.append((e.name + "/", len(os.listdir(e.path)), e.stat().st_mtime_ns))
    except OSError:
        pass
    return out


def _jsonable(v):
    if isinstance(v, np.random.SeedSequence):
        return {"entropy": str(v.entropy), "spawn_key": list(v.spawn_key)}
    if isinstance(v, dict):
        return {k: _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, (np.integer, np.floating)):
        return v.item()
    return v if isinstance(v, (int, float, str, bool, type(None))) else str(v)


def task_fingerprint(task):
    """A hash of everything that determines a task's result: the task itself (algorithm, N, model,
    run, seed stream, config), the content signature of its clip, and the vistrack version. A
    result file whose fingerprint differs is not reused by ``--resume``."""
    import hashlib

    from . import __version__

    body = {"task": _jsonable(task), "version": __version__}
    if "clip" in task:
        body["clip_files"] = _clip_signature(task["clip"])
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()[:20]


def write_task_result(path, result, task=None):
    """Write a task's result JSON atomically (temporary file, then rename); return the path.
    With ``task``, the result records its :func:`task_fingerprint` (what ``--resume`` checks)."""
    path = Path(path)
    if task is not None:
        result = {**result, "fingerprint": task_fingerprint(task)}
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, json.dumps(result))
    return str(path)


def write_atomic(path, text):
    """Write ``text`` to ``path`` whole or not at all: a temporary file beside it, then a rename
    (a crash leaves the old file or none, never half of the new one)."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        tmp.write_text(text)
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)

def task_done(task, out_dir):
    """Whether ``task``'s result file exists, parses, and was computed by this very task (its
    :func:`task_fingerprint`: same clip content, options, seed stream and version) — what
    ``--resume`` may reuse."""
    p = Path(out_dir) / "tasks" / f"{task['name']}.json"
    if not p.is_file():
        return False
    try:
        data = json.loads(p.read_text())
    except (json.JSONDecodeError, OSError, UnicodeDecodeError):
        return False
    return isinstance(data, dict) and data.get("fingerprint") == task_fingerprint(task)


def stale_tasks(tasks, out_dir):
    """The tasks whose result file exists but cannot be reused (another configuration, or damaged)."""
    return [t for t in tasks if (Path(out_dir) / "tasks" / f"{t['name']}.json").is_file()
            and not task_done(t, out_dir)]


def load_task_results(tasks, out_dir):
    return [json.loads((Path(out_dir) / "tasks" / f"{t['name']}.json").read_text()) for t in tasks]


def summarize(results):
    """Per clip × algo × N summaries (list of dicts, in first-seen order) from task results."""
    groups = {}
    for r in results:
        groups.setdefault((r["clip"], r["algo"], r["particles"]), []).append(r)
    out = []
    for (clip, algo, n), rs in groups.items():
        rs = sorted(rs, key=lambda r: r["run"])
        vis = np.array(rs[0]["visible"], bool)
        err = np.array([[np.inf if e is None else e for e in r["error"]] for r in rs])
        lost = np.array([r["lost"] for r in rs], bool) & vis
        ok = ~lost & vis
        p_lost = lost.mean(axis=0)
        with np.errstate(invalid="ignore"):
            err_frame = np.where(ok.any(axis=0), np.sum(np.where(ok, err, 0), axis=0) / ok.sum(axis=0), np.nan)
        ious = np.array([r["iou"] for r in rs])[:, vis]
        success = [float(np.mean(ious > th)) for th in IOU_THRESHOLDS]
        precision20 = float(np.mean(err[:, vis] <= 20.0))
        precision = [float(np.mean(err[:, vis] <= th)) for th in PRECISION_THRESHOLDS]
        every = err[:, vis][np.isfinite(err[:, vis])]
        ms = np.array([np.mean(r["ms"]) for r in rs])
        ess = [e for r in rs for e in r["ess"] if e is not None]
        out.append({
            "clip": clip, "algo": algo, "particles": n, "runs": len(rs),
            "mean_error": float(err[ok].mean()) if ok.any() else None,
            "mean_error_all": float(every.mean()) if every.size else None,
            "p_lost": float(p_lost[vis].mean()) if vis.any() else 0.0,
            "p_lost_final": float(p_lost[-1]),
            "p_lost_per_frame": p_lost.tolist(),
            "error_per_frame": [None if not np.isfinite(v) else float(v) for v in err_frame],
            "success_auc": float(np.mean(success)),
            "success_curve": success,
            "precision_20px": precision20,
            "precision_curve": precision,
            "frames_per_s": float(1e3 / ms.mean()),
            "mean_ess": float(np.mean(ess)) if ess else None,
        })
    return out


def execute(tasks, out_dir, client, *, resume=False, progress=None, key_prefix="vistrack", runner=None):
    """Run the tasks not yet done on a ``distributed.Client``; each writes its own file.

    ``runner(task, out_dir)`` does one task (default :func:`run_task`, one tracking run
    of a clip); it must write ``out_dir/tasks/<name>.json``.

    ``progress(k)`` is called as tasks finish (and once for those skipped on resume).
    """
    from distributed import as_completed

    pending = [t for t in tasks if not (resume and task_done(t, out_dir))]
    if progress and len(tasks) > len(pending):
        progress(len(tasks) - len(pending))
    futs = [client.submit(runner or run_task, t, str(out_dir), key=f"{key_prefix}-{t['name']}", retries=2, pure=False)
            for t in pending]
    for f in as_completed(futs):
        f.result()
        if progress:
            progress(1)
    return len(pending)


def pooled_summary(results):
    """Per (algo, N) over all clips and runs (same frame count): P(lost) per frame, at the
    last frame and averaged, mean error over frames not lost, ms per frame, mean ESS."""
    groups = {}
    for r in results:
        groups.setdefault((r["algo"], r["particles"]), []).append(r)
    out = []
    for (algo, n), rs in groups.items():
        err = np.array([[np.inf if e is None else e for e in r["error"]] for r in rs])
        s = summarize_runs(err, np.array([r["lost"] for r in rs], bool))
        ms = float(np.mean([np.mean(r["ms"]) for r in rs]))
        ess = [e for r in rs for e in r["ess"] if e is not None]
        out.append({"algo": algo, "particles": n, "clips": len({r["clip"] for r in rs}),
                    "runs": len(rs) // max(1, len({r["clip"] for r in rs})),
                    "p_lost_final": s["p_lost_final"], "p_lost_mean": s["p_lost_mean"], "mean_error": s["mean_error"],
                    "ms_per_frame": ms, "frames_per_s": 1e3 / ms, "mean_ess": float(np.mean(ess)) if ess else None,
                    "p_lost_per_frame": s["p_lost_per_frame"].tolist(),
                    "error_per_frame": [None if not np.isfinite(v) else float(v) for v in s["error_per_frame"]]})
    return out


class OutLocked(RuntimeError):
    """Another running process holds the ``--out`` folder."""


@contextmanager
def lock_out(out_dir):
    """Hold ``out_dir/.vistrack.lock`` (pid and host) for the block: one experiment per ``--out``.

    Raises :class:`OutLocked` (one line naming the holder) when a live process holds it; a lock
    left by a dead process on this host is taken over. Re-entrant within a process.
    """
    import socket

    path = Path(out_dir) / ".vistrack.lock"
    me = f"{os.getpid()}@{socket.gethostname()}"
    try:
        fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        holder = path.read_text().strip() if path.is_file() else ""
        if holder == me:
            yield
            return
        pid, _, host = holder.partition("@")
        alive = True
        if host == socket.gethostname() and pid.isdigit():
            try:
                os.kill(int(pid), 0)
            except ProcessLookupError:
                alive = False
            except PermissionError:
                pass
        if alive:
            raise OutLocked(f"{out_dir} is in use by another vistrack process ({holder}); wait for it or "
                            f"choose another --out (remove {path} if that process is gone)") from None
        path.unlink(missing_ok=True)
        fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    with os.fdopen(fd, "w") as f:
        f.write(me)
    try:
        yield
    finally:
        path.unlink(missing_ok=True)
