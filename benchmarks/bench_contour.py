"""Contour tracking speed, side by side in one process (thesis Table 4.1).

Makes one 320x240 synthetic clip and runs the algorithms interleaved round by
round, so that machine noise hits all of them alike. Prints ms per frame split
into decode, feature maps (gray, the smoothed Sobel map and its mean
magnitude), likelihood (``Contour.loglik``), proposal (LS-N-IPS's local search,
LIS's and LLS's translation moves, excluding the likelihood calls inside them)
and resampling; the total (decode excluded, as in ``vistrack reproduce
contour``) and its ratio to the first entry.

    python benchmarks/bench_contour.py [--entries ls-n-ips:30,bootstrap:2000,lis:30,lls:30] [--rounds 3]
"""

import argparse
import tempfile

import numpy as np

from vistrack.appearance.features import FeatureMaps
from vistrack.data_synth.contour_clip import make_contour_clip
from vistrack.io.clips import load_clip
from vistrack.models.contour.model import Contour
from vistrack.registry import make_filter
from vistrack.registry.builders import build_model
from vistrack.system.resources import keep_freed_memory

from _timing import Timer, run_timed, split_table, stepper


def run_once(path, algo, n, seed, timer):
    clip = load_clip(path)
    model = build_model("contour", clip, init_gt="")
    filt = make_filter(algo, model)
    orig = [(Contour, "loglik", timer.wrap(Contour, "loglik", "likelihood"))]
    for name in ("local_search", "loglik_local_grid", "local_mixture"):
        orig.append((Contour, name, timer.wrap(Contour, name, "proposal")))
    if hasattr(filt, "proposal"):
        filt.proposal.sample = timer.timed(filt.proposal.sample, "proposal")
    filt.resample_scheme = timer.timed(filt.resample_scheme, "resampling")
    rng = np.random.default_rng(seed)
    buffers = {}

    def features(frame):
        maps = FeatureMaps(frame, buffers=buffers)
        maps.gradient(model.gradient_sigma)
        return maps

    try:
        return run_timed(clip.source, timer, features, stepper(filt, n, rng))
    finally:
        for owner, name, fn in orig:
            setattr(owner, name, fn)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--entries", default="ls-n-ips:30,bootstrap:2000,lis:30,lls:30,bootstrap:100")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--frames", type=int, default=100)
    args = ap.parse_args()
    entries = [(e.split(":")[0], int(e.split(":")[1])) for e in args.entries.split(",")]
    timers = {e: Timer() for e in entries}
    frames = dict.fromkeys(entries, 0)
    with tempfile.TemporaryDirectory() as d:
        make_contour_clip(d, frames=args.frames, size=(320, 240), seed=1)
        for r in range(args.rounds):
            for e in entries:
                frames[e] += run_once(d, e[0], e[1], r, timers[e])
    print(f"ms per frame at 320x240 ({args.frames}-frame clip, {args.rounds} rounds interleaved)")
    print("\n".join(split_table(timers, frames, decode_in_total=False)))
    print("total = features + filter step (decode excluded, as in reproduce contour); x first = total / the first's")

if __name__ == "__main__":
    keep_freed_memory()  # as the CLI does
    main()
