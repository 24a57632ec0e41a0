"""License-plate tracking speed at 640x480 (thesis §4.5.3: LIS 65 vs bootstrap 48 frames/s).

Makes one synthetic road clip and times, side by side in one process
(algorithms interleaved round by round), the whole per-frame cost of each
algorithm split into decode, feature maps (Sobel, DoGs and the plate's
normalised maps), likelihood, proposal (LIS/LLS moves) and resampling.

    python benchmarks/bench_plate.py [--entries lis:100,bootstrap:750,lls:100,avpf:750] [--rounds 3]
"""

import argparse
import tempfile

import numpy as np

from vistrack.appearance.features import FeatureMaps
from vistrack.data_synth.plate_clip import make_plate_clip
from vistrack.io.clips import load_clip
from vistrack.models.plate.model import PlateLikelihood
from vistrack.registry import make_filter
from vistrack.registry.builders import build_model
from vistrack.system.resources import keep_freed_memory

from _timing import Timer, run_timed, split_table, stepper


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
    buffers = {}

    def features(frame):
        maps = FeatureMaps(frame, buffers=buffers)
        model.lik.maps(maps)
        maps.gx, maps.gy, maps.dog_small, maps.dog_large  # noqa: B018 - computed here, timed as features
        return maps

    try:
        return run_timed(clip.source, timer, features, stepper(filt, n, rng))
    finally:
        for owner, name, fn in orig:
            if owner is PlateLikelihood:
                setattr(owner, name, fn)


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
    print(f"ms per frame at 640x480 ({args.frames}-frame clip, {args.rounds} rounds interleaved)")
    print("\n".join(split_table(timers, frames)))
    print("total = decode + features + filter step; x first = total / the first entry's")

if __name__ == "__main__":
    keep_freed_memory()  # as the CLI does
    main()
