"""Train the detector's plate/non-plate classifier (vistrack/models/plate/classifier.py) and write
its coefficients to vistrack/models/plate_classifier.npz.

Samples: the rectangle candidates (``rectangle_candidates``) of
- rendered plates of both layouts in synthetic road scenes (``detection_frames``, seeds 100-103)
  and over frames of the plate-free real clips (seeds 110-113);
- plate-free synthetic scenes (seed 120) and plate-free real frames;
a candidate with IoU >= 0.6 with the plate's box is a plate, one below 0.3 is not (between: left
out). The real frames are frames 40 and later of each plate-free clip (every 4th): the search
(``vistrack run`` without a box) reads the first 30, and the tests use seeds 5 and 6.

    python benchmarks/train_plate_classifier.py [--frames 120] [--out PATH]
"""

import argparse
from pathlib import Path

import cv2
import numpy as np
from sklearn.linear_model import LogisticRegression

from vistrack.data_synth.plate_clip import detection_frames
from vistrack.io.video import open_video
from vistrack.models.plate.classifier import _WEIGHTS, rectangle_candidates, window_features
from vistrack.scoring.metrics import iou

REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real"
PLATE_FREE = ["girl_otb", "hand_vot2013", "crossing_otb", "soccer_otb", "ball1_vot2015", "head_carphone",
              "hand_palm_phone", "bag_vot"]


def real_frames(first=40, step=4, most=40):
    out = []
    for name in PLATE_FREE:
        d = REAL / name
        if not d.is_dir():
            continue
        video = next((p for p in d.iterdir() if p.suffix in (".mp4", ".avi")), None)
        if video is None:
            continue
        frames = [f for i, f in open_video(video) if i >= first and (i - first) % step == 0]
        out += frames[:most]
    return out


def samples(frames, boxes):
    xs, ys = [], []
    for f, b in zip(frames, boxes):
        g = cv2.cvtColor(f, cv2.COLOR_BGR2GRAY)
        c = rectangle_candidates(g)
        if len(c) == 0:
            continue
        o = np.array([iou(x, b) for x in c]) if b is not None else np.zeros(len(c))
        keep = (o >= 0.6) | (o < 0.3)
        if keep.any():
            xs.append(window_features(g, c[keep]))
            ys.append((o[keep] >= 0.6).astype(int))
    return np.concatenate(xs), np.concatenate(ys)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=120)
    ap.add_argument("--out", default=str(_WEIGHTS))
    args = ap.parse_args()
    n = args.frames
    real = real_frames()
    print(f"{len(real)} plate-free real frames")
    parts = []
    for k, layout in enumerate(("jp", "single-row")):
        parts.append(samples(*detection_frames(n, layout=layout, seed=100 + k)))
        parts.append(samples(*detection_frames(n, layout=layout, seed=102 + k, widths=(50.0, 120.0))))
        if real:
            parts.append(samples(*detection_frames(n, layout=layout, seed=110 + k, backgrounds=real)))
            parts.append(samples(*detection_frames(n, layout=layout, seed=112 + k, backgrounds=real,
                                                   widths=(50.0, 120.0))))
    parts.append(samples(*detection_frames(n, seed=120, with_plate=False)))
    parts.append(samples(real, [None] * len(real)))
    x = np.concatenate([p[0] for p in parts]).astype(float)
    y = np.concatenate([p[1] for p in parts])
    print(f"{y.sum()} plates, {len(y) - y.sum()} other candidates")
    mean, scale = x.mean(axis=0), x.std(axis=0) + 1e-6
    clf = LogisticRegression(C=0.05, max_iter=2000, class_weight={0: 1.0, 1: 5.0})
    clf.fit((x - mean) / scale, y)
    d = clf.decision_function((x - mean) / scale)
    # the threshold: above every training non-plate but the top 0.1 %, at least log-odds 1
    threshold = max(1.0, float(np.quantile(d[y == 0], 0.999)))
    print(f"training: recall {np.mean(d[y == 1] > threshold):.3f}, false {np.mean(d[y == 0] > threshold):.4f} "
          f"at log-odds {threshold:.2f}")
    np.savez(args.out, coef=clf.coef_[0], bias=clf.intercept_[0], mean=mean, scale=scale, threshold=threshold)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
