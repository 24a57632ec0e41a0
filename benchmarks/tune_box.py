"""Defaults of the box model chosen by leave-one-clip-out cross-validation (issue 43).

    python benchmarks/tune_box.py --grid '{"lambda_scale": [10, 20, 40]}'            # a product grid
    python benchmarks/tune_box.py --configs configs.json --seeds 3 --json tune.json   # named configurations
    python benchmarks/tune_box.py --grid '{"dcf_share": [0.3, 0.5]}' --sre            # also OTB's robustness starts

Every candidate configuration — the defaults (``{}``, always the first), then the grid's product or
the named configurations (``--configs FILE``: ``{"name": {options}, ...}``, passed as
``vistrack.Tracker(seed=s, **options)``) — runs on every clip of the corpus (``real_corpus.py``: each
folder under ``../shared/data/real`` with ``groundtruth_rect.txt``) from the start box a user types
(the first ground-truth line in whole pixels), seeds 1..``--seeds``. A configuration's score on a clip
is its success AUC averaged over the seeds.

Printed, per configuration: the in-sample mean over clips; then the cross-validation: for each clip,
the configuration with the best mean over the *other* clips (ties: the earlier one) scored on the
clip left out; their mean is the leave-one-clip-out mean, the number a change must raise. A change
that raises the in-sample mean but not the cross-validated one is not kept. The folds are the clips
in sorted order and the choice is deterministic: the same runs give the same folds and choices.

Runs are cached (``--cache``, JSON lines keyed by the code's digest, the clip, the start, the seed and
the options), so a grid that grows runs only what is new; ``--workers`` processes run them.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from pathlib import Path

import numpy as np
from real_corpus import DATA, SCORE_CACHE, cached_scores, find_clips, sre_starts


def candidates(grid=None, configs=None):
    """``[(name, options)]``: the defaults first, then the named ``configs`` or the product of ``grid``."""
    out = [("defaults", {})]
    if configs:
        out += [(k, dict(v)) for k, v in configs.items()]
    if grid:
        keys = list(grid)
        for values in itertools.product(*(grid[k] for k in keys)):
            opts = dict(zip(keys, values))
            out.append((",".join(f"{k}={json.dumps(v)}" for k, v in opts.items()), opts))
    seen, unique = set(), []
    for name, opts in out:
        key = json.dumps(opts, sort_keys=True)
        if key not in seen:
            seen.add(key)
            unique.append((name, opts))
    return unique


def cross_validate(scores):
    """Leave-one-clip-out choice over ``scores (C configurations, K clips)``.

    Returns
    -------
    chosen : ndarray of shape (K,) int
        For each clip, the configuration with the best mean over the other clips (the first on ties).
    held_out : ndarray of shape (K,)
        That configuration's score on the clip left out.
    """
    scores = np.asarray(scores, float)
    n_clips = scores.shape[1]
    total = scores.sum(axis=1)
    chosen = np.empty(n_clips, int)
    for k in range(n_clips):
        others = (total - scores[:, k]) / max(n_clips - 1, 1)
        chosen[k] = int(np.argmax(others))  # argmax returns the first of equal maxima
    return chosen, scores[chosen, np.arange(n_clips)]


def evaluate(cands, clips, seeds, *, sre=False, cache=SCORE_CACHE, workers=2, model=None):
    """``{(name, clip, start_index): [AUC per seed]}`` for every candidate (start 0: the user's box;
    1.. the robustness starts with ``sre``), cached (:func:`real_corpus.cached_scores`); ``model``: the
    candidates' model (``None``: vistrack's default)."""
    jobs, where = [], []
    for name, opts in cands:
        opts = {"model": model, **opts} if model else opts
        for c in clips:
            starts = [c.user_box] + (sre_starts(c.user_box) if sre else [])
            for si, start in enumerate(starts):
                for s in seeds:
                    jobs.append((c.folder, "vistrack", start, s, opts))
                    where.append((name, c.name, si))
    out = {}
    for w, sc in zip(where, cached_scores(jobs, cache=cache, workers=workers, desc="tune_box")):
        out.setdefault(w, []).append(sc[0])
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--grid", default=None, help='a product grid as JSON: {"option": [values], ...}')
    ap.add_argument("--configs", default=None, help='a JSON file of named configurations: {"name": {options}}')
    ap.add_argument("--seeds", type=int, default=3, help="seeds 1..SEEDS (default 3)")
    ap.add_argument("--sre", action="store_true", help="also OTB's 12 robustness starts (mean per clip)")
    ap.add_argument("--clips", default="", help="clip folder names (default: every one with ground truth)")
    ap.add_argument("--data", default=str(DATA))
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--model", default="box", help="the model the configurations are options of (default box)")
    ap.add_argument("--cache", default=str(SCORE_CACHE), help="the cache of finished runs ('' none)")
    ap.add_argument("--json", default=None, help="write the scores, folds and choices here")
    args = ap.parse_args(argv)
    grid = json.loads(args.grid) if args.grid else None
    configs = json.loads(Path(args.configs).read_text()) if args.configs else None
    cands = candidates(grid, configs)
    clips = find_clips(args.data, [c for c in args.clips.split(",") if c] or None)
    if not clips:
        sys.exit(f"no clip with groundtruth_rect.txt under {args.data}")
    seeds = list(range(1, args.seeds + 1))
    res = evaluate(cands, clips, seeds, sre=args.sre, cache=args.cache or None, workers=args.workers,
                   model=args.model)
    names = [c.name for c in clips]
    scores = np.array([[np.mean(res[(n, c, 0)]) for c in names] for n, _ in cands])
    chosen, held = cross_validate(scores)
    width = max(len(n) for n, _ in cands)
    print(f"{'configuration':<{width}}  in-sample  " + ("SRE" if args.sre else ""))
    for i, (n, _) in enumerate(cands):
        line = f"{n:<{width}}  {scores[i].mean():.4f}"
        if args.sre:
            sre = np.mean([np.mean(res[(n, c, si)]) for c in names for si in range(1, 13)])
            line += f"     {sre:.4f}"
        print(line)
    print("\nleave-one-clip-out: the configuration chosen on the other clips, scored on the one left out")
    for k, c in enumerate(names):
        print(f"  {c:<32} {cands[chosen[k]][0]:<{width}}  {held[k]:.3f}")
    best = int(np.argmax(scores.mean(axis=1)))
    print(f"\nin-sample mean of the best configuration ({cands[best][0]}): {scores[best].mean():.4f}")
    print(f"leave-one-clip-out mean: {held.mean():.4f}")
    if args.json:
        Path(args.json).write_text(json.dumps({
            "clips": names, "seeds": seeds, "configurations": [{"name": n, "options": o} for n, o in cands],
            "scores": scores.tolist(), "chosen": [cands[k][0] for k in chosen], "held_out": held.tolist(),
            "loo_mean": float(held.mean()), "in_sample_best": float(scores[best].mean())}, indent=1))


if __name__ == "__main__":
    main()
