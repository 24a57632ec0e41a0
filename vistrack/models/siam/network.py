"""NanoTrack v3's Siamese network: a backbone that turns crops into features and a head that correlates a
search crop's features with the exemplar's, on onnxruntime (beyond the seeds: the learned likelihood of
:mod:`vistrack.models.siam.model`, thesis 001 §4.5's "any approximation of the likelihood").

The network (``weights/``, the authors' ONNX files with batch and crop sizes made free by
``tools/nanotrack_onnx.py``; Apache-2.0, ``weights/LICENSE``):

backbone
    a crop ``(N, 3, S, S)`` float32, BGR 0–255 (no normalisation) -> features ``(N, 96, S/16, S/16)``
    (fully convolutional, stride 16): the exemplar crop (``S`` = 127) gives ``8 × 8``, a search crop (255)
    ``16 × 16``, a wide search crop (511) ``32 × 32``.
head
    the exemplar's features ``(1, 96, 8, 8)`` and search features ``(N, 96, 16, 16)`` -> per cell of a
    ``15 × 15`` map, two logits (background, object) and four distances (left, top, right, bottom, search-crop
    pixels) from the cell's point to the sides of the object's box. ``wide=True``: the head made for
    ``32 × 32`` search features (a ``31 × 31`` map), whose global pooling makes its logits differ from a
    normal crop's: for finding candidates, not for weighing them.

Cells and points (the authors' convention): cell ``(i, j)`` of an ``M × M`` map lies at
``16 (j - M // 2), 16 (i - M // 2)`` search-crop pixels from the crop's centre, and the crop's pixels are the
frame's scaled by ``S / side`` about the centre it was cut at (:func:`crop`).

Runtime: onnxruntime, one thread, over OpenCV's DNN module (no new dependency there): on one core of the
development machine a 255 crop's backbone took 1.5 ms and the head 1.2 ms on onnxruntime, 4.1 and 2.0 ms on
``cv2.dnn`` (the same outputs within 1e-5; ``docs/experiments.md``).
"""

from __future__ import annotations

import functools
from importlib import resources
from pathlib import Path

import cv2
import numpy as np

__all__ = ["WEIGHTS", "EXEMPLAR", "INSTANCE", "WIDE", "STRIDE", "CONTEXT", "SiamNetwork", "crop", "context_side",
           "cell_points"]

#: the folder of the ONNX files shipped with the package
WEIGHTS = Path(str(resources.files(__package__) / "weights"))
#: the exemplar crop's side (px), the search crop's and the wide search crop's
EXEMPLAR, INSTANCE, WIDE = 127, 255, 511
#: the backbone's stride (crop px per feature cell)
STRIDE = 16
#: the context about the box in the exemplar crop: ``side = sqrt((w + c (w + h)) (h + c (w + h)))``
CONTEXT = 0.5


def context_side(w, h, context=CONTEXT):
    """The side (frame px) of the square the exemplar crop covers for a box ``w × h`` (the authors' ``s_z``):
    ``sqrt((w + p)(h + p))``, ``p = context (w + h)``; arrays broadcast."""
    p = context * (np.asarray(w, float) + np.asarray(h, float))
    return np.sqrt((w + p) * (h + p))


def cell_points(size):
    """The points ``(size * size, 2)`` ``(x, y)`` of a ``size × size`` map's cells, search-crop px from the
    crop's centre, row by row (the authors' ``generate_points``)."""
    ori = -(size // 2) * STRIDE
    xs = ori + STRIDE * np.arange(size, dtype=float)
    x, y = np.meshgrid(xs, xs)
    return np.stack([x.ravel(), y.ravel()], axis=1)


def crop(frame, centre, side, out, fill):
    """The square of ``side`` frame px about ``centre`` ``(cx, cy)`` resized to ``out × out``: ``(3, out, out)``
    float32 BGR, the frame's edges padded with ``fill`` (the frame's mean colour, ``(3,)``).

    As the authors cut it: the square's first pixel is ``floor(c - (side + 1) / 2 + 0.5)`` with ``side`` rounded
    to whole pixels, and OpenCV's bilinear resize (only the padding that the square needs is made)."""
    side = max(1, int(round(float(side))))
    c = (side + 1) / 2
    x0 = int(np.floor(centre[0] - c + 0.5))
    y0 = int(np.floor(centre[1] - c + 0.5))
    h, w = frame.shape[:2]
    x1, y1 = x0 + side, y0 + side
    patch = frame[max(y0, 0):min(y1, h), max(x0, 0):min(x1, w)]
    pads = (max(0, -y0), max(0, y1 - h), max(0, -x0), max(0, x1 - w))
    if any(pads):
        if patch.size == 0:  # the square lies wholly outside the frame
            patch = np.empty((side, side, 3), np.uint8)
            patch[:] = np.asarray(fill, float).round().astype(np.uint8)
        else:
            patch = cv2.copyMakeBorder(patch, *pads, cv2.BORDER_CONSTANT, value=[float(v) for v in fill])
    if side != out:
        patch = cv2.resize(patch, (out, out))
    return np.ascontiguousarray(patch.transpose(2, 0, 1), np.float32)


#: the placeholder of the exemplar head's ``input1`` (``tools/nanotrack_onnx.py``)
PLACEHOLDER_SEED = 20261128


def _options(threads):
    import onnxruntime as ort

    so = ort.SessionOptions()
    so.intra_op_num_threads = threads
    so.inter_op_num_threads = 1
    so.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    so.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    so.log_severity_level = 3
    return so


@functools.lru_cache(maxsize=None)
def _session(path, threads):
    """An onnxruntime session of the ONNX file ``path`` (one per file and process: they are read-only)."""
    import onnxruntime as ort

    return ort.InferenceSession(str(path), _options(threads), providers=["CPUExecutionProvider"])


@functools.lru_cache(maxsize=None)
def _exemplar_head(path):
    """The exemplar head's bytes and the placeholder's bytes in them (``tools/nanotrack_onnx.py``)."""
    data = Path(path).read_bytes()
    ph = np.random.default_rng(PLACEHOLDER_SEED).uniform(-1, 1, (1, 96, 8, 8)).astype(np.float32).tobytes()
    if data.count(ph) != 1:
        raise ValueError(f"{path} does not hold the exemplar's placeholder once (remake it: tools/nanotrack_onnx.py)")
    return data, ph


class SiamNetwork:
    """The backbone and the head of NanoTrack v3, with one exemplar (module docstring).

    Parameters
    ----------
    weights : path
        The folder holding ``nanotrack_backbone.onnx``, ``nanotrack_head.onnx`` and
        ``nanotrack_head_wide.onnx`` (the package's by default).
    threads : int
        onnxruntime's threads per network (1: single-threaded, as every timing of the project).
    """

    def __init__(self, weights=WEIGHTS, threads=1):
        weights = Path(weights)
        missing = [n for n in ("nanotrack_backbone.onnx", "nanotrack_head.onnx", "nanotrack_head_wide.onnx",
                               "nanotrack_head_exemplar.onnx") if not (weights / n).is_file()]
        if missing:
            raise FileNotFoundError(f"the siam model's network is missing {', '.join(missing)} in {weights} "
                                    "(reinstall vistrack: they are package data)")
        self._backbone = _session(weights / "nanotrack_backbone.onnx", int(threads))
        self._head = _session(weights / "nanotrack_head.onnx", int(threads))
        self._wide = weights / "nanotrack_head_wide.onnx", int(threads)
        self._fixed_path, self._threads = weights / "nanotrack_head_exemplar.onnx", int(threads)
        self._fixed = None  # the head made for the exemplar kept (:meth:`set_exemplar`)
        self.z = None

    def features(self, crops):
        """The backbone's features ``(N, 96, S/16, S/16)`` float32 of crops ``(N, 3, S, S)`` or ``(3, S, S)``."""
        x = np.asarray(crops, np.float32)
        return self._backbone.run(None, {"input": x[None] if x.ndim == 3 else x})[0]

    def set_exemplar(self, exemplar_crop, *, fixed=True):
        """Keep the exemplar's features ``(1, 96, 8, 8)`` of an exemplar crop ``(3, 127, 127)``; returns them.

        ``fixed``: also make the head for this exemplar (its branch folded into constants: about a quarter
        faster, the same outputs within 1e-4), which :meth:`head` then runs while :attr:`z` is this exemplar."""
        self.z = np.ascontiguousarray(self.features(exemplar_crop), np.float32)
        self._fixed = None
        if fixed:
            import onnxruntime as ort

            data, ph = _exemplar_head(self._fixed_path)
            sess = ort.InferenceSession(data.replace(ph, self.z.tobytes()), _options(self._threads),
                                        providers=["CPUExecutionProvider"])
            self._fixed = sess, self.z
        return self.z

    def head(self, search, *, wide=False, z=None):
        """The head on search features ``(N, 96, M+1, M+1)`` (``M`` 15, or 31 with ``wide``) against the exemplar
        (``z``, else the one kept): ``(logit (N, M, M), ltrb (N, 4, M, M))`` float32, the object's logit less the
        background's per cell and the distances of the box's sides from the cell's point (search-crop px)."""
        z = self.z if z is None else z
        if not wide and self._fixed is not None and self._fixed[1] is z:
            cls, loc = self._fixed[0].run(None, {"input2": search})
        else:
            sess = _session(*self._wide) if wide else self._head
            cls, loc = sess.run(None, {"input1": z, "input2": search})
        return cls[:, 1] - cls[:, 0], loc

    def search(self, crops, *, wide=False):
        """:meth:`head` of the backbone's features of search crops ``(N, 3, S, S)`` or ``(3, S, S)``."""
        return self.head(self.features(crops), wide=wide)
