"""The runtime for NanoTrack v3's networks (issue 51, item 1): onnxruntime against ``cv2.dnn``, side by side in one
process, one thread each, on the same crops.

    python benchmarks/bench_siam_runtime.py            # ms per call, the fastest of --reps rounds of --calls calls
    python benchmarks/bench_siam_runtime.py --reps 9 --calls 200

Rows: the backbone on a 255 search crop and on the 127 exemplar crop, the head on a search crop's features
(the exemplar's features as an input, as the authors' head takes them), and the siam model's head made for its
exemplar (:meth:`vistrack.models.siam.network.SiamNetwork.set_exemplar`: the exemplar's features are constants of
the graph, onnxruntime only). The outputs of both runtimes agree to 1e-4 (printed).
"""

from __future__ import annotations

import argparse

import cv2
import numpy as np

from vistrack.models.siam.network import EXEMPLAR, INSTANCE, WEIGHTS, SiamNetwork
from vistrack.scoring.metrics import best_ms


def _ms(fn, calls, reps):
    """ms per call of ``fn``: the fastest of ``reps`` rounds of ``calls`` calls (:func:`best_ms`), after a warm-up."""
    fn()
    return best_ms(lambda: [fn() for _ in range(calls)], reps) / calls


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--calls", type=int, default=100)
    a = ap.parse_args()
    cv2.setNumThreads(1)
    rng = np.random.default_rng(0)
    x = rng.uniform(0, 255, (1, 3, INSTANCE, INSTANCE)).astype(np.float32)
    z = rng.uniform(0, 255, (1, 3, EXEMPLAR, EXEMPLAR)).astype(np.float32)
    net = SiamNetwork(threads=1)
    bb = cv2.dnn.readNetFromONNX(str(WEIGHTS / "nanotrack_backbone.onnx"))
    hd = cv2.dnn.readNetFromONNX(str(WEIGHTS / "nanotrack_head.onnx"))

    def dnn_backbone(img):
        bb.setInput(img)
        return bb.forward()

    def dnn_head(zf, xf):
        hd.setInput(zf, "input1")
        hd.setInput(xf, "input2")
        return hd.forward(hd.getUnconnectedOutLayersNames())

    zf, xf = net.features(z), net.features(x).copy()
    net.set_exemplar(z[0], fixed=True)
    zf = zf.copy()  # not the kept exemplar: head(z=zf) runs the general head
    logit, loc = net.head(xf, z=zf)
    cls, dloc = sorted(dnn_head(zf, xf), key=lambda o: o.shape[1])  # cls (1, 2, ...), loc (1, 4, ...)
    fixed_logit, _ = net.head(xf)
    diff = max(float(np.abs(dnn_backbone(x) - xf).max()),
               float(np.abs(logit - (cls[:, 1] - cls[:, 0])).max()), float(np.abs(loc - dloc).max()),
               float(np.abs(fixed_logit - logit).max()))
    rows = [("backbone, 255 search crop", lambda: net.features(x), lambda: dnn_backbone(x)),
            ("backbone, 127 exemplar crop", lambda: net.features(z), lambda: dnn_backbone(z)),
            ("head, the exemplar's features as an input", lambda: net.head(xf, z=zf), lambda: dnn_head(zf, xf)),
            ("head made for its exemplar (siam's)", lambda: net.head(xf), None)]
    print(f"one thread each, the fastest of {a.reps} rounds of {a.calls} calls (outputs agree to {diff:.1e})")
    print(f"{'':44s} {'onnxruntime':>12s} {'cv2.dnn':>9s} {'ratio':>6s}")
    for name, ort_fn, dnn_fn in rows:
        o = _ms(ort_fn, a.calls, a.reps)
        d = _ms(dnn_fn, a.calls, a.reps) if dnn_fn else float("nan")
        print(f"{name:44s} {o:10.2f} ms " + (f"{d:6.2f} ms {d / o:5.2f}x" if dnn_fn else "     (onnxruntime only)"))


if __name__ == "__main__":
    main()
