"""The box model's confidence calibrated on the development clips, and issue 44's checks (one command).

    python benchmarks/fit_confidence.py                 # fit, validate leave-one-clip-out, write the package's file
    python benchmarks/fit_confidence.py --dry-run       # the same, writing nothing
    python benchmarks/fit_confidence.py --check         # issue 44's checks of the shipped model, per clip

The corpus is ``real_corpus.py``'s: every folder under ``../shared/data/real`` with ``groundtruth_rect.txt``,
started from the box a user types (the first ground-truth line in whole pixels), seeds 1..``--seeds``.

Fit
    vistrack's box model runs on every clip and seed with its confidence computed but not acted on
    (``lost_confidence=0``: nothing is reported lost for a low confidence, so the tracks are the model's
    without the confidence); every frame after the first with a true box gives the cues
    (:data:`vistrack.models.box.confidence.FEATURES`) and the label "the estimate's box overlaps the true
    box" (IoU > 0). A logistic regression (scikit-learn, L2, ``C = --C``) on the standardised cues,
    frames weighted so that every clip counts alike; a response or appearance cue
    (:data:`~vistrack.models.box.confidence.MONOTONE`) whose weight comes out negative is dropped and the
    rest refitted, so a sharper response or a closer appearance never lowers the confidence. The threshold
    of ``visible`` is the largest at which at most ``--max-lost`` (3 %) of the frames with IoU >= 0.5 fall
    below it (pooled over the clips, each clip weighted alike). ``--acting`` fits on runs of the shipped
    model instead (its confidence acted on: reported losses, re-detection), a second pass once a first
    calibration is in.
Leave-one-clip-out
    for each clip, the same fit and threshold on the other clips, scored on the clip left out: the ROC
    AUC of the confidence against the label, the log loss, and at that threshold the share of the frames
    in zero-IoU runs of at least 5 frames below it and the share of the frames with IoU >= 0.5 below it.
Written
    ``vistrack/models/box/confidence.npz`` (:class:`~vistrack.models.box.confidence.Calibration`, with the
    clips, seeds and code digest it was fitted on); ``--json FILE`` keeps every number.
Check (``--check``)
    the shipped model (its confidence acted on) on every clip and seed: per clip, the frames in zero-IoU
    runs of at least 5 frames and the share of them reported lost (``visible=0``), the frames with
    IoU >= 0.5 and the share reported lost, the success AUC, the AUC with reported-lost frames scored
    as empty boxes, and VOT-LT's precision, recall and F-score (:func:`vistrack.scoring.metrics.lt_scores`);
    with ``--opencv`` OpenCV's trackers beside it (NanoTrack, CSRT: "visible" is ``update``'s first value).

Runs are cached under ``--cache`` (keyed by vistrack's code and calibration, the clip, start, seed and
options), so a second fit or check runs only what changed; ``--workers`` processes run them.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np
from real_corpus import DATA, ROOT, find_clips, iter_jobs, lost_runs
from tqdm import tqdm

from vistrack.models.box.confidence import CALIBRATION, FEATURES, MONOTONE, SEEN, Calibration
from vistrack.scoring.metrics import iou, lt_scores, success_auc

CACHE = Path.home() / ".cache" / "vistrack" / "fit_confidence"
#: the model's options while the cues are gathered: every cue of the confidence computed, never acted on, no
#: re-detection
OBSERVE = {"lost_confidence": 0.0, "redetect": None, "every_cue": True}
#: ``--acting``: the shipped model, every cue computed
ACTING = {"every_cue": True}


def code_digest(root=ROOT / "vistrack"):
    """SHA-1 of every ``.py`` file under ``root`` and of the shipped calibration: a cached run is reused only
    for the same code and calibration."""
    h = hashlib.sha1()
    for p in sorted(Path(root).rglob("*.py")) + ([CALIBRATION] if CALIBRATION.is_file() else []):
        h.update(str(p.relative_to(root)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


def _save_run(path, run):
    n = len(run.boxes)
    np.savez(path, boxes=run.boxes, visible=run.visible, confidence=run.confidence,
             features=np.full((n, 0), np.nan) if run.features is None else run.features,
             redetected=np.zeros(n, bool) if run.redetected is None else run.redetected,
             reasons=np.array([""] * n) if run.reasons is None else run.reasons,
             candidates=np.full((n, 0, 0), np.nan) if run.candidates is None else run.candidates,
             candidate_boxes=np.full((n, 0, 4), np.nan) if run.candidate_boxes is None else run.candidate_boxes)


def gather(clips, seeds, tracker="vistrack", options=None, *, cache=CACHE, workers=2, digest=None):
    """``{(clip name, seed): {boxes, visible, confidence, features, redetected, reasons}}`` of ``tracker`` (with
    ``options``) from each clip's user box, cached in ``cache``."""
    digest = digest or code_digest()
    cache = Path(cache)
    cache.mkdir(parents=True, exist_ok=True)
    todo, paths = [], {}
    ours = tracker.startswith("vistrack")
    for c in clips:
        for s in seeds if ours else [0]:
            key = json.dumps([digest if ours else "opencv", tracker, c.name, list(c.user_box), s, options or {}],
                             sort_keys=True)
            p = cache / (hashlib.sha1(key.encode()).hexdigest()[:20] + ".npz")
            paths[(c.name, s)] = p
            if not p.is_file():
                todo.append(((c.name, s), p, (c.folder, tracker, c.user_box, s, options or {})))
    if todo:
        bar = tqdm(total=len(todo), desc=f"runs ({tracker})", unit="run", file=sys.stderr)
        for (_, p, _), (_, run) in zip(todo, iter_jobs([j for _, _, j in todo], workers)):
            tmp = p.with_suffix(".tmp.npz")
            _save_run(tmp, run)
            tmp.replace(p)  # each run kept as it finishes: a stopped check resumes
            bar.update()
        bar.close()
    out = {}
    for k, p in paths.items():
        with np.load(p, allow_pickle=False) as d:
            out[k] = {n: d[n] for n in d.files}
    return out


# -- the data set and the fit ----------------------------------------------------------------------
def dataset(clips, runs, frame_cal=None):
    """``(X (M, K), y (M,), iou (M,), clip index (M,), zero-run flag (M,))`` over every run's frames after the
    first that have cues (a frame without a true box: not on the object). With ``frame_cal``, the
    candidates' instead: the whole-frame search's candidate on each frame whose estimate's confidence
    (``frame_cal``) is below its threshold, labelled by the candidate's box."""
    xs, ys, ious, groups, zero = [], [], [], [], []
    for k, c in enumerate(clips):
        for (name, _), r in runs.items():
            if name != c.name:
                continue
            truth = c.truth[: len(r["boxes"])]
            ok = np.all(np.isfinite(r["features"]), axis=1)
            ok[0] = False
            x, boxes = r["features"], r["boxes"]
            zr = lost_runs(r["boxes"], truth)
            if frame_cal is not None:  # every candidate of every low-confidence frame
                ok[ok] = frame_cal(x[ok]) < frame_cal.threshold
                npk = r["candidates"].shape[1]
                x, boxes = r["candidates"].reshape(-1, len(SEEN)), r["candidate_boxes"].reshape(-1, 4)
                truth, zr = np.repeat(truth, npk, axis=0), np.repeat(zr, npk)
                ok = np.repeat(ok, npk) & np.all(np.isfinite(x), axis=1)
            v = np.nan_to_num(iou(boxes, truth), nan=0.0)  # 0 where the truth has no box
            xs.append(x[ok])
            ys.append(v[ok] > 0)
            ious.append(v[ok])
            groups.append(np.full(int(ok.sum()), k))
            zero.append(zr[ok])
    return (np.concatenate(xs), np.concatenate(ys), np.concatenate(ious), np.concatenate(groups),
            np.concatenate(zero))


def _clip_weights(groups):
    """Sample weights ``(M,)`` that give every clip the same total (its frames share it)."""
    counts = np.bincount(groups)
    return (1.0 / counts[groups]) * len(groups) / len(counts)


def fit(X, y, groups, *, C=1.0, names=FEATURES, threshold=0.5):
    """The :class:`Calibration` of cues ``X (M, K)`` (``names``, the first ``K`` of :data:`FEATURES`) against
    labels ``y (M,)`` (module docstring), with ``threshold``."""
    from sklearn.linear_model import LogisticRegression

    names = list(names)
    w = _clip_weights(groups)
    while True:
        cols = [FEATURES.index(n) for n in names]
        Z = X[:, cols]
        mean, scale = Z.mean(axis=0), Z.std(axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        lr = LogisticRegression(C=C, max_iter=2000).fit((Z - mean) / scale, y, sample_weight=w)
        coef = lr.coef_[0]
        bad = [n for n, b in zip(names, coef) if n in MONOTONE and b < 0]
        if not bad:
            return Calibration(tuple(names), mean, scale, coef, float(lr.intercept_[0]), threshold)
        worst = min(bad, key=lambda n: coef[names.index(n)])  # the most negative first, one at a time
        names.remove(worst)


def choose_threshold(conf, ious, groups, max_lost=0.03):
    """The largest confidence threshold at which at most ``max_lost`` of the frames with IoU >= 0.5 lie below
    it, each clip weighted alike (``conf``, ``ious``, ``groups``: ``(M,)`` per frame)."""
    good = ious >= 0.5
    c, g = conf[good], groups[good]
    w = _clip_weights(g)
    order = np.argsort(c)
    share = np.cumsum(w[order]) / w.sum()  # the weighted share of good frames at or below each confidence
    k = int(np.searchsorted(share, max_lost, side="right"))  # frames order[:k] may fall below
    return float(c[order[k]]) if k < len(c) else 1.0


def fit_with_threshold(X, y, ious, groups, *, C=1.0, max_lost=0.03):
    """:func:`fit` and its threshold (:func:`choose_threshold` on its own frames)."""
    cal = fit(X, y, groups, C=C)
    cal.threshold = choose_threshold(cal(X), ious, groups, max_lost)
    return cal


def fit_candidates(runs, clips, frame_cal, *, C=1.0):
    """The candidates' :class:`Calibration` (cues :data:`SEEN`, the estimates' threshold) on the candidates of
    ``runs``' low-confidence frames (:func:`dataset` with ``frame_cal``), and that data set."""
    data = dataset(clips, runs, frame_cal)
    return fit(data[0], data[1], data[3], C=C, names=SEEN, threshold=frame_cal.threshold), data


def _roc_auc(y, score):
    from sklearn.metrics import roc_auc_score

    return float(roc_auc_score(y, score)) if 0 < y.sum() < len(y) else float("nan")


def leave_one_clip_out(clips, runs, *, C=1.0, max_lost=0.03):
    """Per clip: the calibrations fitted on the other clips scored on it (module docstring); the candidates'
    on the candidates of its low-confidence frames (by the fold's estimate calibration): how many, how many
    on the object, and of those taken (confidence at least the threshold) how many on it and how many not."""
    from sklearn.metrics import log_loss

    X, y, ious, groups, zero = dataset(clips, runs)
    rows = []
    for k, c in enumerate(clips):
        held = groups == k
        if not held.any():
            continue
        others = [x for i, x in enumerate(clips) if i != k]
        cal = fit_with_threshold(X[~held], y[~held], ious[~held], groups[~held], C=C, max_lost=max_lost)
        cand, _ = fit_candidates({key: r for key, r in runs.items() if key[0] != c.name}, others, cal, C=C)
        p = cal(X[held])
        low = p < cal.threshold
        z, good = zero[held], ious[held] >= 0.5
        cx, cy = dataset([c], {key: r for key, r in runs.items() if key[0] == c.name}, cal)[:2]
        taken = cand(cx) >= cand.threshold if len(cx) else np.zeros(0, bool)
        rows.append({"clip": c.name, "frames": int(held.sum()), "overlap_share": float(y[held].mean()),
                     "roc_auc": _roc_auc(y[held], p),
                     "log_loss": float(log_loss(y[held], np.clip(p, 1e-6, 1 - 1e-6), labels=[False, True])),
                     "threshold": cal.threshold, "zero_run_frames": int(z.sum()),
                     "zero_run_low": float(low[z].mean()) if z.any() else None, "good_frames": int(good.sum()),
                     "good_low": float(low[good].mean()) if good.any() else None,
                     "candidates": int(len(cy)), "candidates_on": int(cy.sum()), "taken_on": int((taken & cy).sum()),
                     "taken_off": int((taken & ~cy).sum())})
    return rows


def _weights_table(cal, names):
    lines = []
    for n in names:
        w = f"{cal.coef[cal.names.index(n)]:+.3f}" if n in cal.names else "dropped (negative)"
        lines.append(f"  {n:<12} {w}")
    return "\n".join(lines + [f"  intercept    {cal.intercept:+.3f}"])


# -- issue 44's checks ------------------------------------------------------------------------------
def check_rows(clips, runs, name):
    """Per clip, the checks of issue 44 over ``runs`` (module docstring), with pooled totals last."""
    rows, pooled = [], {"zero": 0, "zero_lost": 0, "good": 0, "good_lost": 0}
    for c in clips:
        rs = [r for (n, _), r in runs.items() if n == c.name]
        zero = zlost = good = glost = 0
        auc, auc_lt, lt = [], [], []
        for r in rs:
            truth = c.truth[: len(r["boxes"])]
            present = (truth[:, 2] > 0) & (truth[:, 3] > 0)
            v = iou(r["boxes"], truth)
            vis = r["visible"].astype(bool)
            z = lost_runs(r["boxes"], truth)
            g = present & (v >= 0.5)
            zero, zlost = zero + z.sum(), zlost + (z & ~vis).sum()
            good, glost = good + g.sum(), glost + (g & ~vis).sum()
            auc.append(success_auc(v[present]))
            auc_lt.append(success_auc(np.where(vis, v, 0.0)[present]))
            conf = r["confidence"] if np.isfinite(r["confidence"][1:]).all() else None
            lt.append(lt_scores(r["boxes"], truth, vis, conf))
        pooled.update(zero=pooled["zero"] + zero, zero_lost=pooled["zero_lost"] + zlost, good=pooled["good"] + good,
                      good_lost=pooled["good_lost"] + glost)
        rows.append({"clip": c.name, "tracker": name, "runs": len(rs), "zero_run_frames": int(zero),
                     "zero_run_lost": float(zlost / zero) if zero else None, "good_frames": int(good),
                     "good_lost": float(glost / good) if good else None, "auc": float(np.mean(auc)),
                     "auc_lost_empty": float(np.mean(auc_lt)),
                     **{k: float(np.mean([s[k] for s in lt])) for k in lt[0]}})
    pooled = {k: int(v) for k, v in pooled.items()}
    rows.append({"clip": "all", "tracker": name, "zero_run_frames": pooled["zero"],
                 "zero_run_lost": pooled["zero_lost"] / pooled["zero"] if pooled["zero"] else None,
                 "good_frames": pooled["good"],
                 "good_lost": pooled["good_lost"] / pooled["good"] if pooled["good"] else None,
                 "auc": float(np.mean([r["auc"] for r in rows])),
                 "auc_lost_empty": float(np.mean([r["auc_lost_empty"] for r in rows]))})
    return rows


def _pct(v):
    return "   –" if v is None else f"{100 * v:5.1f}%"


def print_check(rows):
    print(f"{'clip':<32} {'tracker':<9} {'IoU-0 run fr':>12} {'lost':>6} {'IoU>=.5 fr':>10} {'lost':>6} {'AUC':>6} "
          f"{'AUC lt':>6} {'LT Pr':>6} {'LT Re':>6} {'LT F':>6} {'F own':>6}")
    for r in rows:
        lt = "".join(f" {r[k]:6.3f}" if k in r else "      –" for k in ("precision", "recall", "f_score", "f_own"))
        print(f"{r['clip']:<32} {r['tracker']:<9} {r['zero_run_frames']:>12} {_pct(r['zero_run_lost']):>6} "
              f"{r['good_frames']:>10} {_pct(r['good_lost']):>6} {r['auc']:6.3f} {r['auc_lost_empty']:6.3f}{lt}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--seeds", type=int, default=3, help="seeds 1..SEEDS (default 3)")
    ap.add_argument("--clips", default="", help="clip folder names (default: every one with ground truth)")
    ap.add_argument("--data", default=str(DATA))
    ap.add_argument("--C", type=float, default=1.0, help="the logistic regression's inverse L2 strength")
    ap.add_argument("--max-lost", type=float, default=0.03,
                    help="the threshold's bar: this share of the frames with IoU >= 0.5 below it (default 0.03)")
    ap.add_argument("--acting", action="store_true", help="fit on runs of the shipped model (its confidence acted on)")
    ap.add_argument("--check", action="store_true", help="issue 44's checks of the shipped model instead of a fit")
    ap.add_argument("--options", default="{}", type=json.loads,
                    help='with --check: vistrack.Tracker options as JSON, e.g. \'{"confidence": false}\' (the '
                         'confidence not acted on)')
    ap.add_argument("--opencv", default="", help="with --check: OpenCV's trackers beside it, e.g. Nano,CSRT")
    ap.add_argument("--dry-run", action="store_true", help="fit and validate, but write no calibration")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", default=str(CACHE))
    ap.add_argument("--json", default=None, help="write every number here")
    args = ap.parse_args(argv)
    clips = find_clips(args.data, [c for c in args.clips.split(",") if c] or None)
    if not clips:
        sys.exit(f"no clip with groundtruth_rect.txt under {args.data}")
    seeds = list(range(1, args.seeds + 1))
    if args.check:
        runs = gather(clips, seeds, options=args.options or None, cache=args.cache, workers=args.workers)
        rows = check_rows(clips, runs, "vistrack")
        for name in (n for n in args.opencv.split(",") if n):
            rows += check_rows(clips, gather(clips, seeds, name, cache=args.cache, workers=args.workers), name)
        print_check(rows)
        if args.json:
            Path(args.json).write_text(json.dumps({"seeds": seeds, "rows": rows}, indent=1))
        return
    digest = code_digest()
    runs = gather(clips, seeds, "vistrack-probe", ACTING if args.acting else OBSERVE, cache=args.cache,
                  workers=args.workers, digest=digest)
    X, y, ious, groups, _ = dataset(clips, runs)
    cal = fit_with_threshold(X, y, ious, groups, C=args.C, max_lost=args.max_lost)
    cand, (_, cy, *_rest) = fit_candidates(runs, clips, cal, C=args.C)
    loo = leave_one_clip_out(clips, runs, C=args.C, max_lost=args.max_lost)
    print(f"{len(y)} frames of {len(clips)} clips x {len(seeds)} seeds, {100 * y.mean():.1f} % on the object "
          "(IoU > 0)")
    print(f"the estimate's cues, weights (standardised):\n{_weights_table(cal, FEATURES)}\n"
          f"threshold {cal.threshold:.3f}")
    print(f"\n{len(cy)} candidates of whole-frame searches on the low-confidence frames, {100 * cy.mean():.1f} % "
          f"on the object; their cues, weights:\n{_weights_table(cand, SEEN)}")
    print(f"\nleave-one-clip-out (fitted on the other clips):\n{'clip':<32} {'frames':>6} {'IoU>0':>6} {'ROC AUC':>7} "
          f"{'logloss':>7} {'thresh':>6} {'IoU-0 run fr':>12} {'low':>6} {'IoU>=.5 fr':>10} {'low':>6} "
          f"{'cands':>6} {'on':>5} {'taken on':>8} {'off':>4}")
    for r in loo:
        print(f"{r['clip']:<32} {r['frames']:>6} {_pct(r['overlap_share']):>6} {r['roc_auc']:7.3f} "
              f"{r['log_loss']:7.3f} "
              f"{r['threshold']:6.3f} {r['zero_run_frames']:>12} {_pct(r['zero_run_low']):>6} {r['good_frames']:>10} "
              f"{_pct(r['good_low']):>6} {r['candidates']:>6} {r['candidates_on']:>5} {r['taken_on']:>8} "
              f"{r['taken_off']:>4}")
    zr = sum(r["zero_run_frames"] for r in loo)
    gd = sum(r["good_frames"] for r in loo)
    print(f"{'all (pooled)':<32} {'':>6} {'':>6} {np.nanmean([r['roc_auc'] for r in loo]):7.3f} "
          f"{np.mean([r['log_loss'] for r in loo]):7.3f} {'':>6} {zr:>12} "
          f"{_pct(sum(r['zero_run_low'] * r['zero_run_frames'] for r in loo if r['zero_run_frames']) / max(zr, 1)):>6} "
          f"{gd:>10} {_pct(sum(r['good_low'] * r['good_frames'] for r in loo if r['good_frames']) / max(gd, 1)):>6} "
          + " ".join(f"{sum(r[k] for r in loo):>{w}}" for k, w in (("candidates", 6), ("candidates_on", 5),
                                                                   ("taken_on", 8), ("taken_off", 4))))
    if not args.dry_run:
        Calibration.save_all(CALIBRATION, {"frame": cal, "candidate": cand},
                             clips=np.array([c.name for c in clips]), seeds=np.array(seeds), code=np.array(digest),
                             acting=np.array(args.acting), C=np.float64(args.C), max_lost=np.float64(args.max_lost))
        print(f"\nwrote {CALIBRATION.relative_to(ROOT)}")
    if args.json:
        Path(args.json).write_text(json.dumps({
            "seeds": seeds, "frame": {"names": list(cal.names), "coef": cal.coef.tolist(), "intercept": cal.intercept,
                                      "threshold": cal.threshold},
            "candidate": {"names": list(cand.names), "coef": cand.coef.tolist(), "intercept": cand.intercept},
            "leave_one_clip_out": loo}, indent=1))


if __name__ == "__main__":
    main()
