"""The siam model's confidence calibrated on the development clips, leave-one-clip-out (issue 51).

    python benchmarks/fit_siam_confidence.py              # gather, fit, validate leave-one-clip-out, write the file
    python benchmarks/fit_siam_confidence.py --dry-run    # the same, writing nothing

As ``fit_confidence.py`` calibrates the box model's (issue 44), on ``real_corpus.py``'s clips from the box a
user types, seeds 1..``--seeds``:

Gather
    the siam model on every clip and seed with its confidence computed but not acted on
    (``lost_confidence=0``, no re-detection): every frame after the first with a true box gives the cues
    (:data:`vistrack.models.siam.lost.FEATURES`) and the label "the estimate's box overlaps the true box"
    (IoU > 0); every ``--probe``-th frame also a wide search's confirmed candidates
    (:meth:`~vistrack.models.siam.lost.SiamLost.search`, which changes nothing the tracking reads) with their cues
    (:data:`~vistrack.models.siam.lost.SEEN`) and whether the candidate's box overlaps the true box.
Fit
    a logistic regression (scikit-learn, L2, ``C = --C``) on the standardised cues, each clip weighted alike;
    a cue of :data:`~vistrack.models.siam.lost.MONOTONE` whose weight comes out negative is dropped and the
    rest refitted. The threshold is the largest at which at most ``--max-lost`` (3 %) of the frames with
    IoU >= 0.5 fall below it; the candidates' is the lowest at which ``--precision`` (80 %) of the candidates at
    or above it overlap the object.
Leave-one-clip-out
    each clip scored by the fit on the others: ROC AUC, and at that threshold the share of the frames in
    zero-IoU runs of at least 5 frames below it and of the frames with IoU >= 0.5 below it.
Written
    ``vistrack/models/siam/confidence.npz`` (:class:`~vistrack.models.calibration.Calibration`).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import multiprocessing
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from real_corpus import code_digest, find_clips, load_clip, lost_runs
from tqdm import tqdm

from vistrack.models.calibration import Calibration
from vistrack.models.siam.lost import CALIBRATION, FEATURES, MONOTONE, SEEN
from vistrack.scoring.metrics import iou

CACHE = Path.home() / ".cache" / "vistrack" / "fit_siam"
#: the model's options while the cues are gathered: the confidence computed, never acted on, no re-detection
OBSERVE = {"lost_confidence": 0.0, "redetect_after": None}


def gather_one(args):
    """One run: ``(clip folder, seed, probe)`` -> ``(features (T, F), ious (T,), cand (M, S), cand_iou (M,))``."""
    import cv2

    import vistrack

    folder, seed, probe, options = args
    cv2.setNumThreads(1)
    clip = load_clip(folder)
    frames = clip.frames()
    t = vistrack.Tracker(model="siam", seed=seed, **{**OBSERVE, **options})
    n = len(frames)
    feats, boxes = np.full((n, len(FEATURES)), np.nan), np.zeros((n, 4))
    t.init(np.asarray(frames[0]), clip.user_box)
    boxes[0] = t.box_estimate
    cand, cand_box = [], []
    for i in range(1, n):
        t.update(np.asarray(frames[i]))
        boxes[i] = t.box_estimate
        if t.model.features is not None:
            feats[i] = t.model.features
        if probe and i % probe == 0:
            saved = t.model._reported
            t.model._reported = t.model.estimate(t.particles)[:4]
            for _, obs, pose in t.model.search(np.asarray(frames[i])):
                cand.append(t.model.response_cues(obs, pose))
                cand_box.append((i, *t.model.box(np.r_[pose, pose])[0]))
            t.model._reported = saved
    truth = clip.truth[:n]
    cb = np.array(cand_box).reshape(-1, 5)
    cand_iou = iou(cb[:, 1:], truth[cb[:, 0].astype(int)]) if len(cb) else np.zeros(0)
    return feats, iou(boxes, truth), np.array(cand).reshape(-1, len(SEEN)), cand_iou, truth


def gather(clips, seeds, probe, options, workers, cache=CACHE):
    """Every clip's and seed's run (:func:`gather_one`), cached in ``cache`` by the code's digest and the options."""
    key = hashlib.sha1(json.dumps([code_digest(), probe, options], sort_keys=True).encode()).hexdigest()[:12]
    paths = [Path(cache) / f"{key}-{c.name}-{s}.npz" for c in clips for s in seeds]
    jobs = [(c.folder, s, probe, options) for c in clips for s in seeds]
    todo = [(p, j) for p, j in zip(paths, jobs) if not p.is_file()]
    if todo:
        Path(cache).mkdir(parents=True, exist_ok=True)
        ctx = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(workers, mp_context=ctx) as ex:
            for (p, _), r in tqdm(zip(todo, ex.map(gather_one, [j for _, j in todo])), total=len(todo),
                                  desc="gather", file=sys.stderr):
                np.savez(p, **dict(zip(("feats", "ious", "cand", "cand_iou", "truth"), r)))
    out = []
    for p, (folder, *_) in zip(paths, jobs):
        with np.load(p) as d:
            out.append((Path(folder).name, d["feats"], d["ious"], d["cand"], d["cand_iou"], d["truth"]))
    return out


def _weights(groups):
    names, counts = np.unique(groups, return_counts=True)
    per = dict(zip(names, 1.0 / counts))
    return np.array([per[g] for g in groups]) * len(groups) / len(names)


def fit(X, y, groups, names, order, C=1.0, threshold=0.5):
    """A :class:`Calibration` of cue vectors ``X (M, len(order))`` against labels ``y`` over cues ``names``."""
    from sklearn.linear_model import LogisticRegression

    names, w = list(names), _weights(groups)
    while True:
        cols = [order.index(n) for n in names]
        Z = X[:, cols]
        mean, scale = Z.mean(axis=0), Z.std(axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        lr = LogisticRegression(C=C, max_iter=2000).fit((Z - mean) / scale, y, sample_weight=w)
        bad = [n for n, b in zip(names, lr.coef_[0]) if n in MONOTONE and b < 0]
        if not bad:
            return Calibration(tuple(names), mean, scale, lr.coef_[0], float(lr.intercept_[0]), threshold,
                               tuple(order))
        names.remove(min(bad, key=lambda n: lr.coef_[0][names.index(n)]))


def choose_threshold(conf, ious, groups, max_lost):
    """The largest threshold with at most ``max_lost`` of the IoU >= 0.5 frames below it (clips alike)."""
    good = ious >= 0.5
    c, w = conf[good], _weights(groups[good])
    order = np.argsort(c)
    share = np.cumsum(w[order]) / w.sum()
    k = int(np.searchsorted(share, max_lost, side="right"))
    return float(c[order[k]]) if k < len(c) else 1.0


def frames_data(runs):
    """``(X, y, ious, groups, lost)`` over every run's frames after the first with a true box."""
    X, I, G, L = [], [], [], []
    for name, feats, ious, _, _, truth in runs:
        keep = np.isfinite(feats).all(axis=1) & (truth[:, 2] > 0)
        lost = np.zeros(len(ious), bool)
        lost[: len(truth)] = lost_runs_from_iou(ious, truth)
        X.append(feats[keep])
        I.append(ious[keep])
        L.append(lost[keep])
        G += [name] * int(keep.sum())
    X, ious = np.concatenate(X), np.concatenate(I)
    return X, (ious > 0).astype(int), ious, np.array(G), np.concatenate(L)


def lost_runs_from_iou(ious, truth, min_len=5):
    """Frames in runs of at least ``min_len`` with IoU 0 where the truth has a box."""
    fake = np.where((ious > 0)[:, None], truth, truth + 1e6)  # boxes that miss where the IoU is 0
    return lost_runs(fake, truth, min_len)


def candidates_data(runs):
    X, y, G = [], [], []
    for name, _, _, cand, cand_iou, _ in runs:
        X.append(cand)
        y.append(cand_iou > 0)
        G += [name] * len(cand)
    return np.concatenate(X), np.concatenate(y).astype(int), np.array(G)


def calibrate(runs, C, max_lost, precision=0.8):
    X, y, ious, groups, _ = frames_data(runs)
    cal = fit(X, y, groups, FEATURES, FEATURES, C)
    cal.threshold = choose_threshold(cal(X), ious, groups, max_lost)
    cal.threshold, cal.hold = choose_hold(cal, runs, max_lost)
    cX, cy, cg = candidates_data(runs)
    cand = fit(cX, cy, cg, SEEN, SEEN, C)
    cand.threshold = candidate_threshold(cand(cX), cy, cg, precision)
    return cal, cand


def reported_lost(conf, threshold, hold):
    """Which frames ``(T,)`` a run with confidences ``conf (T,)`` (NaN: none, the state kept) reports lost: below
    ``threshold``, and once lost until the confidence reaches ``threshold + hold`` (:class:`SiamLost`'s rule)."""
    lost = np.zeros(len(conf), bool)
    state = False
    for i, c in enumerate(conf):
        if np.isfinite(c):
            state = c < (threshold + hold if state else threshold)
        lost[i] = state
    return lost


def choose_hold(cal, runs, max_lost, lower=(0.0, 0.05, 0.1, 0.15), holds=(0.0, 0.05, 0.1, 0.15, 0.2, 0.25)):
    """``(threshold, hold)``: of the thresholds ``lower`` below ``cal``'s and the holds above them, the pair that
    reports the most frames of zero-IoU runs lost while at most ``max_lost`` of the IoU >= 0.5 frames are (each
    clip alike; the runs' confidences replayed through :func:`reported_lost`)."""
    conf = []
    for _, feats, ious, _, _, truth in runs:
        c = np.full(len(ious), np.nan)
        ok = np.isfinite(feats).all(axis=1)
        c[ok] = cal(feats[ok])
        conf.append((c, lost_runs_from_iou(ious, truth), (ious >= 0.5) & (truth[:, 2] > 0)))
    best = (-1.0, cal.threshold, 0.0)
    for d in lower:
        for h in holds:
            t = cal.threshold - d
            hit = np.array([(reported_lost(c, t, h) & lr).sum() for c, lr, _ in conf])
            bad = np.array([(reported_lost(c, t, h) & g).sum() for c, _, g in conf])
            n_lr = sum(lr.sum() for _, lr, _ in conf)
            n_g = sum(g.sum() for _, _, g in conf)
            if bad.sum() <= max_lost * n_g and hit.sum() / max(n_lr, 1) > best[0]:
                best = (hit.sum() / max(n_lr, 1), t, h)
    return best[1], best[2]


def candidate_threshold(conf, y, groups, precision):
    """The lowest threshold at which at least ``precision`` of the candidates at or above it are right (each clip
    weighted alike): a lost object's candidate is taken from there."""
    w = _weights(groups)
    order = np.argsort(-conf)
    hits = np.cumsum((w * y)[order]) / np.cumsum(w[order])
    ok = np.flatnonzero(hits >= precision)
    return float(conf[order][ok[-1]]) if len(ok) else 1.0


def run_confidence(cal, feats):
    """The confidence ``(T,)`` of a run's cue rows (NaN where a frame has none)."""
    c = np.full(len(feats), np.nan)
    ok = np.isfinite(feats).all(axis=1)
    c[ok] = cal(feats[ok])
    return c


def leave_one_out(runs, clips, C, max_lost):
    """Per clip, by the calibration fitted on the other clips: ``(ROC AUC, share of the frames in zero-IoU runs
    reported lost, share of the IoU >= 0.5 frames reported lost, the two counts, the two lost counts)``."""
    from sklearn.metrics import roc_auc_score

    rows = {}
    for c in clips:
        cal, _ = calibrate([r for r in runs if r[0] != c.name], C, max_lost)
        confs, ys, n = [], [], np.zeros(4, int)
        for _, feats, ious, _, _, truth in (r for r in runs if r[0] == c.name):
            conf = run_confidence(cal, feats)
            lost = reported_lost(conf, cal.threshold, cal.hold)
            lr, good = lost_runs_from_iou(ious, truth), (ious >= 0.5) & (truth[:, 2] > 0)
            n += [lr.sum(), good.sum(), (lost & lr).sum(), (lost & good).sum()]
            keep = np.isfinite(conf) & (truth[:, 2] > 0)
            confs.append(conf[keep])
            ys.append(ious[keep] > 0)
        y, conf = np.concatenate(ys), np.concatenate(confs)
        auc = float(roc_auc_score(y, conf)) if 0 < y.sum() < len(y) else float("nan")
        rows[c.name] = (auc, n[2] / n[0] if n[0] else float("nan"), n[3] / n[1] if n[1] else float("nan"),
                        *(int(v) for v in n))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--probe", type=int, default=10, help="a wide search's candidates every PROBE frames")
    ap.add_argument("--C", type=float, default=1.0)
    ap.add_argument("--max-lost", type=float, default=0.03)
    ap.add_argument("--precision", type=float, default=0.8, help="of the candidates taken (their threshold)")
    ap.add_argument("--options", default="{}", help="the siam model's options (JSON) while gathering")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--dry-run", action="store_true")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    clips = find_clips()
    runs = gather(clips, list(range(1, args.seeds + 1)), args.probe, json.loads(args.options), args.workers)
    rows = leave_one_out(runs, clips, args.C, args.max_lost)
    print(f"{'clip':<32} {'ROC AUC':>8} {'lost runs low':>14} {'IoU>=.5 low':>12}")
    for name, (auc, lost, good, *_) in rows.items():
        print(f"{name:<32} {auc:8.3f} {lost:14.3f} {good:12.3f}")
    tot = np.array([r[3:] for r in rows.values()], float)
    print(f"pooled: {tot[:, 2].sum() / max(tot[:, 0].sum(), 1):.3f} of {int(tot[:, 0].sum())} frames in zero-IoU runs "
          f"reported lost, {tot[:, 3].sum() / max(tot[:, 1].sum(), 1):.3f} of {int(tot[:, 1].sum())} frames with "
          "IoU >= 0.5 (leave-one-clip-out)")
    cal, cand = calibrate(runs, args.C, args.max_lost, args.precision)
    print("frame calibration:", dict(zip(cal.names, np.round(cal.coef, 3))), "threshold", round(cal.threshold, 4),
          "hold", round(cal.hold, 3))
    print("candidate calibration:", dict(zip(cand.names, np.round(cand.coef, 3))), "threshold",
          round(cand.threshold, 4))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"leave_one_out": rows, "threshold": cal.threshold}, fh, indent=1)
    if not args.dry_run:
        Calibration.save_all(CALIBRATION, {"frame": cal, "candidate": cand}, clips=np.array([c.name for c in clips]),
                             seeds=np.arange(1, args.seeds + 1), code=np.array(code_digest()))
        print(f"wrote {CALIBRATION}")


if __name__ == "__main__":
    main()
