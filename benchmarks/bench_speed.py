"""The speed targets of issue 22, measured in one interleaved run (rounds of every entry in turn,
so that machine noise hits them alike).

1. Decode-only rate of each clip (``open_video``, frames read and dropped) beside the ``vistrack
   run``-equivalent end-to-end rate (:func:`vistrack.session.recording.record_video` on the prefetched frames,
   the stage timers on, decode included; model building and the kernels' loading excluded, as start-up)
   of the three paths: contour
   LS-N-IPS-30 at 320x240, plate LIS-100 at 640x480 (synthetic; and the real dashcam clip with its
   appearance learned from the first box) and box LIS-100 at 640x480 (car4 resized). Target: end to
   end >= 25 % of decode-only.
2. Tracking frames/s (frames decoded beforehand; feature maps and filter step, as ``reproduce``
   times them) of LS-N-IPS-30 vs bootstrap-2000 on a 320x240 contour clip (target >= 10x in every
   round) and of plate LIS-100 vs bootstrap-750 at 640x480 (target >= 1.5x).
3. Tracking time per frame (``init`` + ``update``, frames in memory) of the default box tracker
   (LIS-100) vs OpenCV's KCF on the real clips with ground truth (target: less than KCF). KCF is in
   opencv-contrib-python-headless; without it the column says so.

    python benchmarks/bench_speed.py [--rounds 3] [--contour-frames 200] [--plate-frames 150] [--parts 1,2,3] \
        [--only plate]

``--cpu`` times parts 2 and 3 in process CPU time (``time.process_time``) instead of wall time: on a
machine loaded by other work, wall time mostly measures the scheduler (part 1 stays wall time: its
end-to-end runs overlap decoding in a thread).

Both vistrack and OpenCV run single-threaded here (``cv2.setNumThreads(1)``); the decode thread of
the end-to-end runs is the one extra thread, as in ``vistrack run``.
"""

import argparse
import tempfile
import time
import warnings
from pathlib import Path

import cv2
import numpy as np
from real_corpus import opencv_tracker  # run from benchmarks/

import vistrack
from vistrack.data_synth.contour_clip import make_contour_clip
from vistrack.data_synth.plate_clip import make_plate_clip
from vistrack.io.clips import load_clip
from vistrack.io.video import groundtruth_origin, open_video, prefetch, read_rects
from vistrack.loop import Stepper, warm_up
from vistrack.registry import make_filter
from vistrack.registry.builders import build_model
from vistrack.session.recording import record_video
from vistrack.system.resources import keep_freed_memory

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "real"
CLOCK = time.perf_counter  # --cpu: time.process_time
REAL = ["girl_otb", "hand_vot2013", "car4_otb_first100", "plate_in_polo_dashcam"]


def real_clip(name):
    """Frames (in memory) and the 0-based ground-truth boxes of a real clip."""
    folder = DATA / name
    frames = [f for _, f in open_video(next(folder.glob("*.mp4")))]
    path = folder / "groundtruth_rect.txt"
    return frames, read_rects(path, origin=groundtruth_origin(path))[: len(frames)]


def write_resized(name, out, size):
    """A real clip resized to ``size`` (an mp4 and its 1-based OTB ground truth) in folder ``out``."""
    frames, gt = real_clip(name)
    out.mkdir()
    sx, sy = size[0] / frames[0].shape[1], size[1] / frames[0].shape[0]
    w = cv2.VideoWriter(str(out / "video.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, size)
    for f in frames:
        w.write(cv2.resize(f, size, interpolation=cv2.INTER_LINEAR))
    w.release()
    np.savetxt(out / "groundtruth_rect.txt", gt * [sx, sy, sx, sy] + [1, 1, 0, 0], fmt="%.3f", delimiter=",")
    return out


def decode_rate(path):
    """Frames/s of decoding alone."""
    t0, n = time.perf_counter(), 0
    for _ in open_video(path):
        n += 1
    return n / (time.perf_counter() - t0)


def e2e_rate(folder, model_name, algo, n, seed, **build):
    """Frames/s of a ``vistrack run``-equivalent run (decode included, start-up excluded)."""
    clip = load_clip(folder)
    model = build_model(model_name, clip, **build)
    filt = make_filter(algo, model)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = record_video(prefetch(clip.source), model, filt, n, np.random.default_rng(seed))
    return len(run.rows) / run.wall


def tracking_rate(folder, frames, model_name, algo, n, seed, **build):
    """Frames/s of the frame loop alone over frames in memory (feature maps and filter step)."""
    model = build_model(model_name, load_clip(folder), **build)
    filt = make_filter(algo, model)
    warm_up(filt, n, frames[0])  # the compiled kernels loaded: start-up, not tracking
    stepper = Stepper(filt, n, np.random.default_rng(seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = CLOCK()
        for i, f in enumerate(frames):
            stepper.step(i, f)
    return len(frames) / (CLOCK() - t0)


def box_ms(frames, box, seed):
    """ms per frame of the default box tracker (``init`` + ``update``)."""
    t = vistrack.Tracker(model="box", particles=100, seed=seed)
    t0 = CLOCK()
    t.init(frames[0], box)
    for f in frames[1:]:
        t.update(f)
    return 1e3 * (CLOCK() - t0) / len(frames)


def kcf_ms(frames, box):
    """ms per frame of OpenCV's KCF (``init`` + ``update``), or NaN without opencv-contrib."""
    tr = opencv_tracker("KCF")
    if tr is None:
        return float("nan")
    t0 = CLOCK()
    tr.init(frames[0], tuple(int(round(v)) for v in box))
    for f in frames[1:]:
        tr.update(f)
    return 1e3 * (CLOCK() - t0) / len(frames)


def clips(tmp, args):
    """The clip folders of the end-to-end runs: (label, folder, model, algo, N, build options)."""
    contour = tmp / "contour320"
    make_contour_clip(contour, frames=args.contour_frames, size=(320, 240), seed=1)
    plate = tmp / "plate640"
    make_plate_clip(plate, frames=args.plate_frames, seed=1)
    box = write_resized("car4_otb_first100", tmp / "car4_640", (640, 480))
    return [("contour 320x240 LS-N-IPS-30", contour, "contour", "ls-n-ips", 30, {"init_gt": ""}),
            ("plate 640x480 LIS-100", plate, "plate", "lis", 100, {}),
            ("plate dashcam 552x530 LIS-100", DATA / "plate_in_polo_dashcam", "plate", "lis", 100, {"init_gt": ""}),
            ("box car4 640x480 LIS-100", box, "box", "lis", 100, {"init_gt": ""})]


def one_round(r, paths, mem, real, res, parts=(1, 2, 3)):
    """Every entry of ``parts`` once, in turn, with seed ``r``; appends to ``res``."""
    if 3 in parts:
        for name, (frames, gt) in real.items():
            res.setdefault(("box", name), []).append(box_ms(frames, gt[0], r))
            res.setdefault(("kcf", name), []).append(kcf_ms(frames, gt[0]))
    if 1 in parts:
        e2e_round(r, paths, res)
    if 2 not in parts:
        return
    for key, pair, build in (("contour", (("ls-n-ips", 30), ("bootstrap", 2000)), {"init_gt": ""}),
                             ("plate", (("lis", 100), ("bootstrap", 750)), {})):
        if key in mem:
            folder, frames = mem[key]
            for algo, n in pair:
                res.setdefault((key, algo), []).append(tracking_rate(folder, frames, key, algo, n, r, **build))


def e2e_round(r, paths, res):
    """Part 1 once: decode-only and end-to-end rates of every path."""
    for label, folder, model, algo, n, build in paths:
        res.setdefault(("decode", label), []).append(decode_rate(load_clip(folder).source.path))
        res.setdefault(("e2e", label), []).append(e2e_rate(folder, model, algo, n, r, **build))


def report(res, paths, real, rounds, parts=(1, 2, 3)):
    if 1 in parts:
        report_e2e(res, paths)
    if 2 in parts:
        report_ratios(res, rounds)
    if 3 not in parts:
        return
    print("\n3. box LIS-100 (the default tracker) vs KCF, tracking ms per frame (init + update), median of rounds")
    print(f"{'clip':<24} {'size':>9} {'box':>7} {'KCF':>7} {'box/KCF':>8}  box/KCF per round")
    for name, (frames, _) in real.items():
        b, k = np.array(res[("box", name)]), np.array(res[("kcf", name)])
        size = f"{frames[0].shape[1]}x{frames[0].shape[0]}"
        print(f"{name:<24} {size:>9} {np.median(b):>7.2f} {np.median(k):>7.2f} {np.median(b) / np.median(k):>8.2f}  "
              + " ".join(f"{v:.2f}" for v in b / k))


def report_e2e(res, paths):
    print("\n1. end to end (vistrack run, decode included) vs decode only, frames/s, median of rounds")
    print(f"{'path':<32} {'decode':>8} {'e2e':>8} {'e2e/decode':>11}  per round")
    for label, *_ in paths:
        d, e = np.array(res[("decode", label)]), np.array(res[("e2e", label)])
        print(f"{label:<32} {np.median(d):>8.0f} {np.median(e):>8.0f} {np.median(e / d):>11.3f}  "
              + " ".join(f"{v:.3f}" for v in e / d))


def report_ratios(res, rounds):
    for what, (a, b), target in (("contour 320x240", (("ls-n-ips", 30), ("bootstrap", 2000)), 10.0),
                                 ("plate 640x480", (("lis", 100), ("bootstrap", 750)), 1.5)):
        if (what.split()[0], a[0]) not in res:
            continue
        x, y = np.array(res[(what.split()[0], a[0])]), np.array(res[(what.split()[0], b[0])])
        print(f"\n2. {what}: tracking frames/s (frames in memory), target ratio >= {target:g} in every round")
        na, nb = f"{a[0]}-{a[1]}", f"{b[0]}-{b[1]}"
        print(f"{'round':<6} {na:>16} {nb:>16} {'ratio':>7}")
        for k in range(rounds):
            print(f"{k:<6} {x[k]:>16.1f} {y[k]:>16.1f} {x[k] / y[k]:>7.2f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--contour-frames", type=int, default=200)
    ap.add_argument("--plate-frames", type=int, default=150)
    ap.add_argument("--data", type=Path, default=None, help="the real clips' folder [default: ../shared/data/real]")
    ap.add_argument("--cpu", action="store_true", help="process CPU time instead of wall time (parts 2 and 3)")
    ap.add_argument("--parts", default="1,2,3", help="which parts to run, comma-separated [default: 1,2,3]")
    ap.add_argument("--only", choices=("contour", "plate", "box"), default=None, help="one path's entries alone")
    args = ap.parse_args()
    parts = tuple(int(p) for p in args.parts.split(",") if p)
    global DATA, CLOCK
    DATA = args.data or DATA
    CLOCK = time.process_time if args.cpu else time.perf_counter
    cv2.setNumThreads(1)
    if opencv_tracker("KCF") is None:
        print(f"KCF is not in this OpenCV ({cv2.__version__}): its column is nan "
              "(opencv-contrib-python-headless has it)")
    real = {name: real_clip(name) for name in REAL if (DATA / name).is_dir() and args.only in (None, "box")}
    with tempfile.TemporaryDirectory() as d:
        paths = [p for p in clips(Path(d), args) if Path(p[1]).is_dir()] if {1, 2} & set(parts) else []
        mem = {k: (paths[i][1], [f for _, f in open_video(load_clip(paths[i][1]).source.path)])
               for i, k in ((0, "contour"), (1, "plate")) if 2 in parts and args.only in (None, k)}
        paths = [p for p in paths if args.only in (None, p[2])]
        for frames, gt in real.values():  # start-up: the kernels and OpenCV's trackers loaded
            box_ms(frames[:3], gt[0], 0)
            kcf_ms(frames[:3], gt[0])
        res = {}
        for r in range(args.rounds):
            t0 = time.perf_counter()
            one_round(r, paths, mem, real, res, parts)
            print(f"round {r}: {time.perf_counter() - t0:.0f} s", flush=True)
        report(res, paths, real, args.rounds, parts)


if __name__ == "__main__":
    keep_freed_memory()  # as the CLI does
    main()
