"""The box model with the correlation filter (issue 34) on every real clip with ground truth, seeds 1-3.

    python benchmarks/box_dcf_diag.py [--seeds 1,2,3] [--clips ...] [--opts '{"lambda_dcf": 20}']
                                      [--opencv MIL,KCF,CSRT] [--fresh]

Prints per clip the mean success AUC over seeds, the worst seed, precision at 20 px and tracking-only
frames/s (``bench_real``'s timing: init + update, frames decoded beforehand), and the mean over clips.
OpenCV's trackers do not depend on the seed: their rows are cached in ``/tmp/vistrack_opencv_rows.json``
(``--fresh``: run again, as many times as there are seeds, so that their frames/s, the median, come from
the same run as vistrack's). ``--opts`` is a JSON
dict of box-model options (``vistrack.Tracker(model="box", **opts)``).
"""

import argparse
import json
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import vistrack  # noqa: E402
from vistrack.core.metrics import box_scores as scores  # noqa: E402
from vistrack.core.runtime import keep_freed_memory  # noqa: E402

from bench_real import DATA, load, opencv_tracker, run_opencv  # noqa: E402

ALL = ["girl_otb", "hand_vot2013", "car4_otb_first100", "plate_in_polo_dashcam", "crossing_otb", "soccer_otb",
       "ball1_vot2015"]
CACHE = Path("/tmp/vistrack_opencv_rows.json")


def run(frames, box, seed, opts, n=100):
    import time

    t = vistrack.Tracker(model="box", algo="lis", particles=n, seed=seed, **opts)
    t0 = time.perf_counter()
    t.init(frames[0], box)
    out = [t.box_estimate]
    for f in frames[1:]:
        t.update(f)
        out.append(t.box_estimate)
    return np.array(out), time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--clips", default=",".join(ALL))
    ap.add_argument("--opts", default="{}")
    ap.add_argument("--opencv", default="")
    ap.add_argument("--particles", type=int, default=100)
    ap.add_argument("--fresh", action="store_true", help="run the OpenCV trackers again (their frames/s from this "
                                                           "run, for speed ratios) and refresh the cache")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    seeds = [int(s) for s in args.seeds.split(",")]
    opts = json.loads(args.opts)
    cache = json.loads(CACHE.read_text()) if CACHE.exists() else {}
    means, rows = [], {}
    # warm the compiled kernels outside the timings
    frames, gt, _ = load(DATA / "car4_otb_first100")
    run(frames[:5], gt[0], 0, opts)
    print(f"{'clip':<24} {'tracker':<10} {'AUC':>6} {'worst':>6} {'P@20':>6} {'frames/s':>9}")
    for clip in args.clips.split(","):
        frames, gt, _ = load(DATA / clip)
        runs = [run(frames, gt[0], s, opts, args.particles) for s in seeds]
        sc = np.array([scores(b, gt) for b, _ in runs])
        fps = len(frames) / np.median([t for _, t in runs])
        means.append(sc[:, 0].mean())
        print(f"{clip:<24} {'vistrack':<10} {sc[:, 0].mean():>6.3f} {sc[:, 0].min():>6.3f} {sc[:, 1].mean():>6.3f} "
              f"{fps:>9.0f}  seeds " + " ".join(f"{v:.3f}" for v in sc[:, 0]), flush=True)
        for name in [c for c in args.opencv.split(",") if c]:
            key = f"{clip}/{name}"
            if (args.fresh or key not in cache) and opencv_tracker(name) is not None:
                timed = [run_opencv(frames, gt, name) for _ in range(len(seeds) if args.fresh else 1)]
                b, t = timed[0][0], np.median([t for _, t in timed])  # deterministic: the same boxes each time
                cache[key] = [*map(float, scores(b, gt)), len(frames) / t]
                CACHE.write_text(json.dumps(cache))
            if key in cache:
                a, p, _, f = cache[key]
                rows.setdefault(name, []).append(a)
                print(f"{clip:<24} {name:<10} {a:>6.3f} {a:>6.3f} {p:>6.3f} {f:>9.0f}"
                      + (f"  vistrack/{name} speed {fps / f:.1f}x" if args.fresh else ""))
    print(f"mean AUC vistrack {np.mean(means):.3f} " + " ".join(f"{k} {np.mean(v):.3f}" for k, v in rows.items()))


if __name__ == "__main__":
    keep_freed_memory()
    main()
