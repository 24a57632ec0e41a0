"""License-plate tracking speed at 640x480 (thesis §4.5.3: LIS 65 vs bootstrap 48 frames/s).

Makes one synthetic road clip and times, side by side in one process
(algorithms interleaved round by round), the whole per-frame cost of each
algorithm split into decode, feature maps (Sobel, DoGs and the plate's
normalised maps), likelihood, proposal (LIS/LLS moves) and resampling.

    python benchmarks/bench_plate.py [--entries lis:100,bootstrap:750,lls:100,avpf:750] [--rounds 3]
"""

import argparse
import tempfile
import time
import warnings

import numpy as np

from vistrack.builders import build_model
from vistrack.clips import load_clip
from vistrack.data_synth.plate import make_plate_clip
from vistrack.features import FeatureMaps
from vistrack.filters import make_filter
from vistrack.models.plate import PlateLikelihood
from vistrack.runtime import keep_freed_memory

from _timing import Timer


def run_once(path, algo, n, seed, timer):
    clip = load_clip(path)
    model = build_model("plate", clip)
    filt = make_filter(algo, model)
    orig = [(PlateLikelihood, "loglik", timer.wrap(PlateLikelihood, "loglik", "likelihood"))]
    if hasattr(filt, "proposal"):
        orig.append((filt.proposal, "sample", timer.wrap(filt.proposal, "sample", "proposal")))
    if algo == "lls":  # LLS's proposal is its grid of sparse likelihoods
        orig.append((model, "loglik_local_grid", timer.wrap(model, "loglik_local_grid", "proposal")))
    filt.resample_scheme = timer.timed(filt.resample_scheme, "resampling")
    rng = np.random.default_rng(seed)
    p, buffers, frames = None, {}, 0
    it = iter(clip.source)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            while True:
                t0 = time.perf_counter()
                try:
                    _, frame = next(it)
                except StopIteration:
                    break
                t1 = time.perf_counter()
                maps = FeatureMaps(frame, buffers=buffers)
                model.lik.maps(maps)
                maps.gx, maps.gy, maps.dog_small, maps.dog_large  # noqa: B018 - computed here, timed as features
                t2 = time.perf_counter()
                p = filt.first_step(maps, n, rng) if p is None else filt.step(p, maps, rng)
                t3 = time.perf_counter()
                timer.t["decode"] += t1 - t0
                timer.t["features"] += t2 - t1
                timer.t["filter"] += t3 - t2
                frames += 1
    finally:
        for owner, name, fn in orig:
            if owner is PlateLikelihood:
                setattr(owner, name, fn)
    return frames


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--entries", default="lis:100,bootstrap:750,lls:100,avpf:750")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--frames", type=int, default=150)
    args = ap.parse_args()
    entries = [(e.split(":")[0], int(e.split(":")[1])) for e in args.entries.split(",")]
    timers = {e: Timer() for e in entries}
    frames = dict.fromkeys(entries, 0)
    with tempfile.TemporaryDirectory() as d:
        make_plate_clip(d, frames=args.frames, seed=1)
        for r in range(args.rounds):
            for e in entries:
                frames[e] += run_once(d, e[0], e[1], r, timers[e])
    parts = ["decode", "features", "likelihood", "proposal", "resampling"]
    print(f"ms per frame at 640x480 ({args.frames}-frame clip, {args.rounds} rounds interleaved)")
    print(f"{'algo':<10} {'N':>5} " + " ".join(f"{p:>10}" for p in parts) + f" {'other':>8} {'total':>8} {'frames/s':>9}")
    for e, tm in timers.items():
        k = 1e3 / frames[e]
        total = (tm.t["decode"] + tm.t["features"] + tm.t["filter"]) * k
        other = tm.t["filter"] * k - (tm.t["likelihood"] + tm.t["proposal"] + tm.t["resampling"]) * k
        print(f"{e[0]:<10} {e[1]:>5} " + " ".join(f"{tm.t[p] * k:>10.2f}" for p in parts)
              + f" {other:>8.2f} {total:>8.2f} {1e3 / total:>9.0f}")


if __name__ == "__main__":
    keep_freed_memory()  # as the CLI does
    main()
