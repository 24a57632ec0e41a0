"""The fixed crops of the network's stored reference (``nanotrack_v3_reference.npz``): smooth BGR patterns of
sines, float32 0-255, made the same way by the test and by the command that wrote the reference::

    python tests/models/siam/reference_crops.py ../shared/data/baselines/nanotrack_v3

which runs the authors' ONNX files on OpenCV's DNN module (a runtime independent of vistrack's) and writes the
exemplar's features and the head's outputs beside this file."""

import sys
from pathlib import Path

import numpy as np

REFERENCE = Path(__file__).with_name("nanotrack_v3_reference.npz")


def pattern(side, phase):
    """A ``(3, side, side)`` float32 crop: a sum of sines per channel (values 0..255)."""
    i, j = np.meshgrid(np.arange(side, dtype=np.float64), np.arange(side, dtype=np.float64), indexing="ij")
    out = np.empty((3, side, side), np.float32)
    for c in range(3):
        a = phase + 1.7 * c
        v = np.sin(i * 0.11 + a) + np.sin(j * 0.07 - 0.5 * a) + np.sin((i + j) * 0.031 + 2 * a)
        out[c] = 127.5 + 40.0 * v
    return out


def write(source):
    import cv2

    z, x = pattern(127, 0.3), pattern(255, 1.1)
    nb = cv2.dnn.readNet(str(Path(source) / "nanotrack_backbone.onnx"))
    nh = cv2.dnn.readNet(str(Path(source) / "nanotrack_head.onnx"))
    nb.setInput(z[None])
    fz = nb.forward().copy()
    nb.setInput(x[None])
    fx = nb.forward().copy()
    nh.setInput(fz, "input1")
    nh.setInput(fx, "input2")
    cls, loc = nh.forward(["output1", "output2"])
    np.savez_compressed(REFERENCE, z_features=fz[0], cls=cls[0], loc=loc[0])


if __name__ == "__main__":
    write(sys.argv[1])
