"""A NanoTrack v3 speed reference (issue 53) until its baseline lands: its two ONNX networks timed per frame
beside vistrack's box model and ``cv2.TrackerNano`` (v2), in one process, single-threaded, on the same decoded
frames of every real clip with ground truth.

    python benchmarks/v3_nets_speed.py [--json v3.json]

Per frame, as the official tracker's update (``../shared/data/baselines/nanotrack_v3/SOURCE.txt``): the 255x255
search crop (context 0.5, the channel average of the first frame as its border) about the previous frame's
ground-truth box, the backbone on it (``cv2.dnn``), the head on it and the exemplar's features, and the peak of
the object-minus-background logit map; the exemplar's backbone once. The cosine window, the penalties and the
box regression's few hundred operations are left out, so the v3 figure is an upper bound on its speed. Each
tracker the fastest of three runs.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import cv2
import numpy as np
from real_corpus import DATA, find_clips, run_opencv, run_vistrack

V3 = Path(__file__).resolve().parents[2] / "shared" / "data" / "baselines" / "nanotrack_v3"


def crop(frame, box, out, avg):
    """The ``out x out`` crop about ``box`` with context 0.5 (``out`` 127: the exemplar's, 255: the search's)."""
    x, y, w, h = box
    c = 0.5 * (w + h)
    s = np.sqrt((w + c) * (h + c)) * out / 127
    k = out / s
    m = np.array([[k, 0, out / 2 - k * (x + w / 2)], [0, k, out / 2 - k * (y + h / 2)]])
    return cv2.warpAffine(frame, m, (out, out), borderMode=cv2.BORDER_CONSTANT, borderValue=avg)


def v3_seconds(nets, frames, truth, start):
    """Seconds of the v3 networks' updates over ``frames[1:]`` (module docstring)."""
    backbone, head = nets
    avg = frames[0].mean(axis=(0, 1)).tolist()
    backbone.setInput(cv2.dnn.blobFromImage(crop(frames[0], start, 127, avg)))
    z = backbone.forward().copy()
    t0 = time.perf_counter()
    prev = start
    for k in range(1, len(frames)):
        backbone.setInput(cv2.dnn.blobFromImage(crop(frames[k], prev, 255, avg)))
        head.setInput(z, "input1")
        head.setInput(backbone.forward(), "input2")
        cls = next(o for o in head.forward(head.getUnconnectedOutLayersNames()) if o.shape[1] == 2)
        np.unravel_index(np.argmax(cls[0, 1] - cls[0, 0]), cls.shape[2:])
        if np.all(np.isfinite(truth[k])) and truth[k][2] > 0:
            prev = tuple(truth[k])
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", help="write the rows here")
    ap.add_argument("--data", default=str(DATA))
    args = ap.parse_args()
    cv2.setNumThreads(1)
    nets = tuple(cv2.dnn.readNetFromONNX(str(V3 / f"nanotrack_{p}.onnx")) for p in ("backbone", "head"))
    rows = []
    for clip in find_clips(args.data):
        frames = np.ascontiguousarray(clip.frames())
        n, truth = len(frames), np.asarray(clip.truth, float)
        run_vistrack(frames[:5], clip.user_box, 1)  # the kernels loaded before any clock
        best = {"vistrack": np.inf, "Nano": np.inf, "v3": np.inf}
        for _ in range(3):
            best["vistrack"] = min(best["vistrack"], run_vistrack(frames, clip.user_box, 1).seconds)
            best["Nano"] = min(best["Nano"], run_opencv(frames, clip.user_box, "Nano").seconds)
            best["v3"] = min(best["v3"], v3_seconds(nets, frames, truth, clip.user_box))
        r = {"clip": clip.name, "frames": n, **{k + "_fps": n / v for k, v in best.items()},
             "vs_nano": best["Nano"] / best["vistrack"], "vs_v3": best["v3"] / best["vistrack"]}
        rows.append(r)
        print(f"{clip.name:32s} {n:5d} vistrack {r['vistrack_fps']:6.0f}  v2 {r['Nano_fps']:5.0f}  "
              f"v3 nets {r['v3_fps']:5.0f}  x v2 {r['vs_nano']:.2f}  x v3 {r['vs_v3']:.2f}", flush=True)
    print(f"median clip: {np.median([r['vs_nano'] for r in rows]):.2f}x v2, "
          f"{np.median([r['vs_v3'] for r in rows]):.2f}x the v3 networks")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
