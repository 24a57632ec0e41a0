"""Does decoding overlap with tracking? The decode rate of ``vistrack run``'s prefetch thread
(:func:`vistrack.io.video.prefetch`) alone and while another thread tracks (contour LS-N-IPS-30 on a
320x240 clip, frames in memory, over and over), in interleaved rounds.

A compiled kernel that holds the GIL stalls the decoding thread each time it needs the GIL (to
hand a frame over), however many cores are idle; the contour kernels release it (``nogil``).

    python benchmarks/bench_overlap.py [--rounds 3] [--frames 200]
"""

import argparse
import tempfile
import threading
import time
import warnings
from pathlib import Path

import cv2
import numpy as np

from vistrack.data_synth.contour_clip import make_contour_clip
from vistrack.io.clips import load_clip
from vistrack.io.video import open_video, prefetch
from vistrack.loop import Stepper, warm_up
from vistrack.registry import make_filter
from vistrack.registry.builders import build_model


def decode_rate(clip, busy):
    """Frames/s of the prefetch thread over ``clip``, with ``busy()`` running in another thread
    until the decoding ends (``busy=None``: nothing else)."""
    stop = threading.Event()
    worker = threading.Thread(target=lambda: busy and busy(stop))
    worker.start()
    t0, n = time.perf_counter(), 0
    for _ in prefetch(clip.source):
        n += 1
    dt = time.perf_counter() - t0
    stop.set()
    worker.join()
    return n / dt


def tracker(clip, frames):
    """``busy(stop)``: LS-N-IPS-30 over ``frames`` again and again until ``stop`` is set."""
    model = build_model("contour", clip, init_gt="")
    filt = make_filter("ls-n-ips", model)
    warm_up(filt, 30, frames[0])

    def busy(stop):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            while not stop.is_set():
                stepper = Stepper(filt, 30, np.random.default_rng(0))
                for i, f in enumerate(frames):
                    if stop.is_set():
                        return
                    stepper.step(i, f)

    return busy


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--frames", type=int, default=200)
    args = ap.parse_args()
    cv2.setNumThreads(1)
    with tempfile.TemporaryDirectory() as d:
        make_contour_clip(Path(d), frames=args.frames, size=(320, 240), seed=1)
        clip = load_clip(Path(d))
        busy = tracker(clip, [f for _, f in open_video(clip.source.path)])
        print(f"{'round':<6} {'decode alone':>13} {'beside tracking':>16} {'ratio':>6}")
        for r in range(args.rounds):
            alone, beside = decode_rate(clip, None), decode_rate(clip, busy)
            print(f"{r:<6} {alone:>13.0f} {beside:>16.0f} {beside / alone:>6.2f}", flush=True)


if __name__ == "__main__":
    main()
