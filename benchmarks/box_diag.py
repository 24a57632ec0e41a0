"""Where and why the box model (LIS-100) loses its object on a real clip with ground truth.

For each seed: the success AUC and the runs of frames with IoU < 0.1 (3 frames or more); with
``--around`` the frames about the first such run, each with the likelihood's parts at the
ground-truth box and at the estimate, computed on the frame before the model adapts to it:
``in`` = ``-λ_c d²(h_in, q)``, ``ring`` = ``-λ_c κ (1 - d²(h_ring, q))``, ``contr`` = the
back-projection contrast, ``tmpl`` = ``λ_t (ncc - 1)`` (:mod:`vistrack.models.box.appearance`).
Truth above the estimate: the search did not reach it; below: the model prefers the estimate.

    python benchmarks/box_diag.py [--clip hand_vot2013] [--seeds 0,8] [--around 8]
"""

import argparse

import numpy as np

import vistrack
from vistrack.core.metrics import iou
from vistrack.models.box.model import Box

from bench_real import load, scores


def parts(app, frame, boxes):
    """``(K, 4)`` likelihood parts (in, ring, contrast, template) of ``boxes (K, 4)`` (cx, cy, w, h)."""
    c, b = app.colour, np.asarray(boxes, float)
    obs = app.frame(frame, app.roi(b, margin=5))
    inner, ring = obs.histograms(b[:, 0], b[:, 1], b[:, 2], b[:, 3], grow=app.ring * 0.5 * (b[:, 2] + b[:, 3]))
    contrast = (inner @ c._bp) / np.maximum(inner.sum(-1), 1) - (ring @ c._bp) / np.maximum(ring.sum(-1), 1)
    return np.stack([-c.lambda_colour * c.d2(inner), -c.lambda_colour * c.kappa * (1 - c.d2(ring)),
                     c.lambda_colour * contrast, app.lambda_template * (app.ncc(obs, b) - 1)], 1)


def run(frames, gt, seed):
    """Boxes ``(T, 4)`` of one run and per frame the parts at ``[truth, estimate]`` before adapting."""
    rec, orig = [], Box.adapt

    def adapt(self, obs, est):
        g = gt[len(rec)]
        both = np.array([[g[0] + g[2] / 2, g[1] + g[3] / 2, g[2], g[3]], self.boxes(est)[0]])
        rec.append((parts(self.app, frames[len(rec)], both), orig(self, obs, est)))
        return rec[-1][1]

    Box.adapt = adapt
    try:
        t = vistrack.Tracker(model="box", algo="lis", particles=100, seed=seed)
        t.init(frames[0], gt[0])
        boxes = [t.box] + [t.update(f)[1] for f in frames[1:]]
    finally:
        Box.adapt = orig
    return np.array(boxes), rec


def lost_runs(v, low=0.1, least=3):
    """``[(first, last)]`` frames of the runs of ``v < low`` at least ``least`` long."""
    out, i = [], 0
    while i < len(v):
        j = i
        while j < len(v) and v[j] < low:
            j += 1
        if j - i >= least:
            out.append((i, j - 1))
        i = j + 1 if j == i else j
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clip", default="hand_vot2013")
    ap.add_argument("--seeds", default="0,8")
    ap.add_argument("--around", type=int, default=0, help="frames shown before and after the first loss")
    args = ap.parse_args()
    frames, gt = load(args.clip)
    gc = gt[:, :2] + gt[:, 2:] / 2
    for seed in (int(s) for s in args.seeds.split(",")):
        boxes, rec = run(frames, gt, seed)
        v, runs = iou(boxes, gt), lost_runs(iou(boxes, gt))
        print(f"seed {seed}: AUC {scores(boxes, gt)[0]:.3f}, adapted on {sum(a for _, a in rec)} frames, "
              f"IoU < 0.1 on {int((v < 0.1).sum())} frames, runs {runs}")
        if not (args.around and runs):
            continue
        print("frame   IoU  err px | truth: in ring contr tmpl = log r | estimate: in ring contr tmpl = log r")
        for i in range(max(runs[0][0] - args.around, 1), min(runs[0][0] + args.around, len(frames))):
            p = rec[i][0]
            err = np.hypot(*(boxes[i, :2] + boxes[i, 2:] / 2 - gc[i]))
            print(f"{i:5d} {v[i]:5.2f} {err:7.1f} | " + " | ".join(
                " ".join(f"{x:5.1f}" for x in row) + f" = {row.sum():6.1f}" for row in p))


if __name__ == "__main__":
    main()
