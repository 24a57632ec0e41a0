"""vistrack's box, contour and plate models beside OpenCV's trackers on the real clips, in one run.

For every real clip with ground truth (``../shared/data/real``) each tracker starts from the
first ground-truth box; frames are decoded once and held in memory, so only tracking is
timed (``init`` + ``update``: for vistrack the whole per-frame step, feature maps included).
Prints success AUC (IoU thresholds 0, 0.05, .., 1), precision at 20 px, the mean centre
error over all frames (a failed OpenCV update holds its last box) and frames/s, then the
box model's time split at 640x480 (car4 resized) beside the OpenCV trackers on the same frames.

    python benchmarks/bench_real.py [--entries lis:100,bootstrap:100,contour/lis:100,plate/lis:100] [--seeds 3]
                                    [--clips girl_otb,hand_vot2013,plate_in_polo_dashcam] [--opencv '']

Entries are ``[model/]algo:N``: the box model by default; ``contour/`` (colour term on for
colour video) and ``plate/`` (the plate clip only, ``--layout single-row``, its appearance
learned from the first box) as ``vistrack run --model ...`` runs them.

OpenCV's MIL is in opencv-python-headless; KCF and CSRT need opencv-contrib-python-headless
(a drop-in replacement); missing ones are skipped with a note. Both run single-threaded
(``cv2.setNumThreads(1)``), as vistrack does.
"""

import argparse
import time
from pathlib import Path

import cv2
import numpy as np

import vistrack
from vistrack.metrics import iou
from vistrack.models.appearance import Appearance
from vistrack.models.box import Box
from vistrack.proposals import MapProposal
from vistrack.runtime import keep_freed_memory
from vistrack.video import groundtruth_origin, open_video, read_rects

from _timing import Timer

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "real"
CLIPS = ["girl_otb", "hand_vot2013", "car4_otb_first100", "plate_in_polo_dashcam"]
THRESHOLDS = np.linspace(0.0, 1.0, 21)


def opencv_tracker(name):
    """``cv2.Tracker<name>`` from this OpenCV build, or ``None``."""
    for ns in (cv2, getattr(cv2, "legacy", None)):
        if ns is not None and hasattr(ns, f"Tracker{name}_create"):
            return getattr(ns, f"Tracker{name}_create")()
    cls = getattr(cv2, f"Tracker{name}", None)
    return cls.create() if cls is not None and hasattr(cls, "create") else None


def load(name, size=None):
    folder = DATA / name
    frames = [f for _, f in open_video(next(folder.glob("*.mp4")))]
    gt = read_rects(folder / "groundtruth_rect.txt", origin=groundtruth_origin(folder / "groundtruth_rect.txt"))
    gt = gt[: len(frames)]
    if size is not None:
        sx, sy = size[0] / frames[0].shape[1], size[1] / frames[0].shape[0]
        frames = [cv2.resize(f, size, interpolation=cv2.INTER_LINEAR) for f in frames]
        gt = gt * np.array([sx, sy, sx, sy])
    return frames, gt


def run_vistrack(frames, box, algo, n, seed, model="box"):
    opts = {"layout": "single-row"} if model == "plate" else {}
    t = vistrack.Tracker(model=model, algo=algo, particles=n, seed=seed, **opts)
    t0 = time.perf_counter()
    t.init(frames[0], box)
    out = [t.box]
    for f in frames[1:]:
        out.append(t.update(f)[1])
    return np.array(out), time.perf_counter() - t0


def run_opencv(frames, box, name):
    tr = opencv_tracker(name)
    b = tuple(int(round(v)) for v in box)
    t0 = time.perf_counter()
    tr.init(frames[0], b)
    out, last = [b], b
    for f in frames[1:]:
        ok, r = tr.update(f)
        last = tuple(r) if ok else last
        out.append(last)
    return np.array(out, float), time.perf_counter() - t0


def scores(boxes, gt):
    v = iou(boxes, gt)
    c = np.hypot(*(boxes[:, :2] + boxes[:, 2:] / 2 - gt[:, :2] - gt[:, 2:] / 2).T)
    return np.mean([(v > t).mean() for t in THRESHOLDS]), (c <= 20).mean(), c.mean()


def split(frames, box, n, timer):
    """The box model's LIS-``n`` per-part seconds on ``frames`` into ``timer``."""
    orig = [(Appearance, "loglik", timer.wrap(Appearance, "loglik", "likelihood")),
            (MapProposal, "sample", timer.wrap(MapProposal, "sample", "proposal")),
            (Box, "observe", timer.wrap(Box, "observe", "features")),
            (Box, "adapt", timer.wrap(Box, "adapt", "adapt")),
            (Box, "lis_step", timer.wrap(Box, "lis_step", "proposal"))]  # compiled: the likelihood inside
    try:
        t = vistrack.Tracker(model="box", algo="lis", particles=n, seed=0)
        t.init(frames[0], box)
        filt = t._stepper.filt
        filt.resampler.scheme = timer.timed(filt.resampler.scheme, "resampling")
        t0 = time.perf_counter()
        for f in frames[1:]:
            t.update(f)
        timer.t["total"] += time.perf_counter() - t0
    finally:
        for owner, name, fn in orig:
            setattr(owner, name, fn)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--entries", default="lis:100,bootstrap:100,ls-n-ips:100,contour/lis:100,plate/lis:100",
                    help="[model/]algo:N, model box (default), contour or plate (the plate clip only, "
                         "single-row layout)")
    ap.add_argument("--opencv", default="MIL,KCF,CSRT")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--clips", default=",".join(CLIPS), help="clips of the real-clip folder, comma-separated")
    args = ap.parse_args()
    clips = [c for c in args.clips.split(",") if c]
    cv2.setNumThreads(1)
    entries = []
    for e in args.entries.split(","):
        spec, n = e.split(":")
        model, algo = spec.split("/") if "/" in spec else ("box", spec)
        entries.append((model, algo, int(n)))
    cvs = [c for c in args.opencv.split(",") if c and opencv_tracker(c) is not None]
    missing = sorted(set(args.opencv.split(",")) - set(cvs) - {""})
    if missing:
        print(f"not in this OpenCV ({cv2.__version__}): {', '.join(missing)} (opencv-contrib-python-headless has them)")
    print(f"{'clip':<24} {'tracker':<16} {'AUC':>6} {'P@20':>6} {'err px':>7} {'frames/s':>9}")
    means = {}
    for clip in clips:
        if not (DATA / clip).is_dir():
            print(f"{clip}: not found under {DATA}")
            continue
        frames, gt = load(clip)
        rows = []
        for model, algo, n in entries:
            if model == "plate" and not clip.startswith("plate"):
                continue
            runs = [run_vistrack(frames, gt[0], algo, n, s, model) for s in range(args.seeds)]
            sc = np.mean([scores(b, gt) for b, _ in runs], axis=0)
            name = f"{algo}-{n}" if model == "box" else f"{model}/{algo}-{n}"
            rows.append((name, sc, len(frames) / np.median([t for _, t in runs])))
        for name in cvs:
            b, t = run_opencv(frames, gt[0], name)
            rows.append((name, scores(b, gt), len(frames) / t))
        for name, sc, fps in rows:
            means.setdefault(name, []).append(sc[0])
            print(f"{clip:<24} {name:<16} {sc[0]:>6.3f} {sc[1]:>6.3f} {sc[2]:>7.1f} {fps:>9.0f}")
    print("mean AUC: " + ", ".join(f"{k} {np.mean(v):.3f}" for k, v in means.items()))
    if "car4_otb_first100" in clips and (DATA / "car4_otb_first100").is_dir():
        frames, gt = load("car4_otb_first100", size=(640, 480))
        timer = Timer()
        split(frames, gt[0], 100, timer)
        k = 1e3 / (len(frames) - 1)
        parts = ["features", "likelihood", "proposal", "resampling", "adapt"]
        other = timer.t["total"] - sum(timer.t[p] for p in parts)
        print("\nbox LIS-100 at 640x480 (car4 resized), ms per frame (the compiled LIS step's likelihood counts "
              "as proposal): " + ", ".join(
            f"{p} {timer.t[p] * k:.2f}" for p in parts) + f", other {other * k:.2f}, total {timer.t['total'] * k:.2f}"
            f" ({1e3 / (timer.t['total'] * k):.0f} frames/s)")
        for name in cvs:
            _, t = run_opencv(frames, gt[0], name)
            print(f"{name} on the same frames: {len(frames) / t:.0f} frames/s")


if __name__ == "__main__":
    keep_freed_memory()
    main()
