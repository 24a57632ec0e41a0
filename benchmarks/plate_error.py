"""Plate LIS-100 against bootstrap-750: the error of frames not lost (the seed figure since issue 6:
LIS-100's at most 1.05x bootstrap-750's), on synthetic road clips, run for run.

Makes ``--seeds`` clips (``vistrack synth plate``, 640x480, ``--frames`` frames; cached in ``--cache``),
tracks each ``--runs`` times with every entry as ``vistrack eval`` does (its runner, started from the first
ground-truth box, the plate lost rule; run r of every entry draws from the same seed stream), in
``--workers`` processes, and prints per entry: ``vistrack eval``'s "mean error, not lost" (per clip, then
averaged over clips) and its ratio to the reference entry's; the same over the frames that both the entry
and the reference track in the same run (paired frames); the ratio's 95 % interval (:func:`ratio_interval`: the
runs of each clip resampled, the entries kept paired); P(lost). Each ``--variant NAME=VALUE,...`` runs
the first entry again with those defaults of the plate model's LIS proposal (``PlateLISProposal``) set in
its workers (the reference once), to try them side by side.

    python benchmarks/plate_error.py --seeds 7101-7103 --runs 20
    python benchmarks/plate_error.py --seeds 201-206 --runs 10 --variant cells=32 --variant cells=48
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import tempfile
from collections import defaultdict
from pathlib import Path

import numpy as np


def _seeds(text):
    a, _, b = text.partition("-")
    return list(range(int(a), int(b or a) + 1))


def make_clips(cache, seeds, frames):
    """The clip folders of ``seeds`` in ``cache`` (made when missing)."""
    from vistrack.data_synth.plate_clip import make_plate_clip

    out = []
    for s in seeds:
        clip = Path(cache) / f"plate-{s}-{frames}"
        if not (clip / "groundtruth.csv").is_file():
            make_plate_clip(clip, frames=frames, size=(640, 480), seed=s)
        out.append(clip)
    return out


_VARIANT = {}


def _init(variant):
    """A worker: the proposal's defaults replaced by ``variant``."""
    if variant:
        from vistrack.models.plate import proposal

        init = proposal.PlateLISProposal.__init__
        defaults = dict(zip(init.__code__.co_varnames[2:init.__code__.co_argcount], init.__defaults__))
        defaults.update(variant)
        init.__defaults__ = tuple(defaults.values())


def _run(args):
    task, out = args
    from vistrack.evaluation.experiment import run_task

    return run_task(task, out)


def track(clips, entries, runs, seed, out, workers, variant=None):
    """Every task of the evaluation of ``entries`` into ``out/tasks`` (the proposal's defaults ``variant``);
    returns their results."""
    from vistrack.evaluation.experiment import EvalConfig

    cfg = EvalConfig(clips=[str(c) for c in clips], algos=[a for a, _ in entries],
                     particles=sorted({n for _, n in entries}), runs=runs, seed=seed, model="plate",
                     entries=list(entries))
    tasks = cfg.tasks()
    with mp.get_context("spawn").Pool(workers, initializer=_init, initargs=(variant,)) as pool:
        paths = pool.map(_run, [(t, out) for t in tasks], chunksize=1)
    return [json.loads(Path(p).read_text()) for p in paths]


def _not_lost_mean(by, keys, entry):
    """eval's "mean error, not lost" of ``entry`` over the runs ``keys`` ((clip, run) pairs): per clip, then
    averaged over clips."""
    clips = sorted({c for c, _ in keys})
    return float(np.mean([np.mean([x for k in keys if k[0] == c for x, q in zip(by[k][entry]["error"],
                                                                              by[k][entry]["lost"])
                                    if x is not None and not q]) for c in clips]))


def ratio_interval(results, entry, ref, draws=2000, seed=0):
    """The 95 % interval of the ratio of ``entry``'s to ``ref``'s "mean error, not lost", the runs of each
    clip resampled with replacement, the two entries' runs kept paired (run r of both, the same seed stream)."""
    by = defaultdict(dict)
    for r in results:
        by[(r["clip"], r["run"])][(r["algo"], r["particles"])] = r
    keys = sorted(by)
    clips = sorted({c for c, _ in keys})
    rng = np.random.default_rng(seed)
    reps = []
    for _ in range(draws):
        sample = []
        for c in clips:
            runs = [k for k in keys if k[0] == c]
            sample += [runs[i] for i in rng.integers(0, len(runs), len(runs))]
        reps.append(_not_lost_mean(by, sample, entry) / _not_lost_mean(by, sample, ref))
    return tuple(float(v) for v in np.percentile(reps, [2.5, 97.5]))


def summary(results, entries):
    """``{entry: {mean_not_lost, paired, p_lost}}``: eval's mean error of frames not lost (per clip,
    averaged over clips), the mean over the frames the entry and the reference (the last entry) both
    track in the same run, and P(lost)."""
    by = defaultdict(dict)
    for r in results:
        by[(r["clip"], r["run"])][(r["algo"], r["particles"])] = r
    ref = entries[-1]
    out = {}
    for e in entries:
        per_clip, pa, pb, lost = defaultdict(list), [], [], []
        for (clip, _), d in by.items():
            a, b = d[e], d[ref]
            ok = [x for x, q in zip(a["error"], a["lost"]) if x is not None and not q]
            per_clip[clip] += ok
            lost += a["lost"]
            for x, y, p, q in zip(a["error"], b["error"], a["lost"], b["lost"]):
                if x is not None and y is not None and not p and not q:
                    pa.append(x)
                    pb.append(y)
        out[e] = {"mean_not_lost": float(np.mean([np.mean(v) for v in per_clip.values()])),
                  "paired": float(np.mean(pa)), "paired_ref": float(np.mean(pb)), "p_lost": float(np.mean(lost))}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="7101-7103", help="Clip seeds, A-B.")
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0, help="eval --seed of the runs.")
    ap.add_argument("--entries", default="lis:100,bootstrap:750", help="ALGO:N pairs; the last is the reference.")
    ap.add_argument("--workers", type=int, default=mp.cpu_count())
    ap.add_argument("--cache", default=str(Path(tempfile.gettempdir()) / "vistrack-plate-error"))
    ap.add_argument("--variant", action="append", default=[],
                    help="NAME=VALUE,... of PlateLISProposal for the first entry, run again (repeatable).")
    ap.add_argument("--json", help="Write the per-entry numbers here.")
    args = ap.parse_args()
    entries = [(e.split(":")[0], int(e.split(":")[1])) for e in args.entries.split(",")]
    variants = [{k: json.loads(v) for k, v in (kv.split("=", 1) for kv in x.split(","))} for x in args.variant]
    clips = make_clips(args.cache, _seeds(args.seeds), args.frames)
    print(f"{len(clips)} clips ({args.seeds}), {args.runs} runs")
    print("| entry | variant | mean error, not lost (px) | ratio | 95 % interval | paired frames: entry / reference "
          "(px) | ratio | P(lost) | ms/frame |\n|---|---|---|---|---|---|---|---|---|")
    rows = {}
    with tempfile.TemporaryDirectory() as out:
        base = track(clips, entries, args.runs, args.seed, out, args.workers)
        for name, results in [("", base)] + [(v, track(clips, entries[:1], args.runs, args.seed, f"{out}/{k}",
                                                       args.workers, v)) for k, v in enumerate(variants)]:
            results += [r for r in base if (r["algo"], r["particles"]) != entries[0]] if name else []
            s = summary(results, entries)
            ref = s[entries[-1]]
            for e in (entries if not name else entries[:1]):
                v = s[e]
                ms = np.mean([np.mean(r["ms"]) for r in results if (r["algo"], r["particles"]) == e])
                lo, hi = ratio_interval(results, e, entries[-1]) if e != entries[-1] else (1.0, 1.0)
                rows[f"{e[0]}:{e[1]} {name or ''}".strip()] = {**v, "interval": [lo, hi]}
                print(f"| {e[0]}-{e[1]} | {name or '-'} | {v['mean_not_lost']:.4f} | "
                      f"{v['mean_not_lost'] / ref['mean_not_lost']:.3f} | {lo:.3f}-{hi:.3f} | {v['paired']:.4f} / "
                      f"{v['paired_ref']:.4f} | {v['paired'] / v['paired_ref']:.3f} | {v['p_lost']:.3f} | {ms:.1f} |",
                      flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1, default=str))


if __name__ == "__main__":
    main()
