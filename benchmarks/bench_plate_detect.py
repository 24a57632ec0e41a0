"""Plate on real footage (issue 35), side by side in one run: the detection stage's time per
640x480 frame while it searches, and plate LIS-N tracking frames/s beside the box model's on the
dashcam clip (both from the first ground-truth box, frames decoded once, in memory, after a
warm-up run of each).

    python benchmarks/bench_plate_detect.py [--n 100] [--frames 30]
"""

import argparse
import time
from pathlib import Path

import cv2
import numpy as np

import vistrack
from vistrack.data_synth.plate_clip import detection_frames
from vistrack.io.video import open_video, read_rects
from vistrack.models.plate.detect import PlateDetector
from vistrack.system.resources import keep_freed_memory

CLIP = Path(__file__).resolve().parents[2] / "shared" / "data" / "real" / "plate_in_polo_dashcam"


def per_frame_ms(det, frames, rounds=3):
    best = np.inf
    for _ in range(rounds):
        t0 = time.perf_counter()
        for f in frames:
            det.detect(f)
        best = min(best, (time.perf_counter() - t0) / len(frames))
    return 1e3 * best


def track_fps(model, frames, box, n, seed):
    t = vistrack.Tracker(model=model, algo="lis", particles=n, seed=seed)
    t0 = time.perf_counter()
    t.init(frames[0], box)
    for f in frames[1:]:
        t.update(f)
    return len(frames) / (time.perf_counter() - t0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--frames", type=int, default=30)
    args = ap.parse_args()
    cv2.setNumThreads(1)
    det = PlateDetector()
    frames = [f for _, f in open_video(next(CLIP.glob("*.mp4")))]
    gt = read_rects(CLIP / "groundtruth_rect.txt")
    dash = [cv2.resize(f, (640, 480)) for f in frames[: args.frames]]
    scenes = detection_frames(args.frames, layout="single-row", seed=5)[0] + \
        detection_frames(args.frames, seed=6, with_plate=False)[0]
    print(f"detection, ms per 640x480 frame (best of 3): dashcam resized {per_frame_ms(det, dash):.1f}, "
          f"synthetic road scenes {per_frame_ms(det, scenes):.1f}")
    for model in ("box", "plate"):  # warm-up: the compiled kernels loaded from numba's cache, not timed
        track_fps(model, frames[:5], gt[0], args.n, 1)
    for model in ("box", "plate", "box", "plate"):  # interleaved, twice
        fps = np.median([track_fps(model, frames, gt[0], args.n, s) for s in (1, 2)])
        size = f"{frames[0].shape[1]}x{frames[0].shape[0]}"
        print(f"{model} LIS-{args.n} on the dashcam clip ({size}): {fps:.0f} frames/s")


if __name__ == "__main__":
    keep_freed_memory()
    main()
