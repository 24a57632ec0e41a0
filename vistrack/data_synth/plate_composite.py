"""A rendered plate composited onto the car of a real clip, with exact ground truth.

The car's ground-truth box (e.g. ``car4_otb_first100``: a car seen from behind) gives where: the
plate's centre sits at ``centre`` (shares of the car box's width and height) and its width is
``width`` times the car's, fronto-parallel like the car's rear. The car box of OTB is drawn by hand
and jitters by a few pixels from frame to frame; it is smoothed over ``2 smooth + 1`` frames (a
moving average) so the plate moves as the car does. Per frame:

1. The plate (:func:`~vistrack.data_synth.plate_clip.render_plate`, 240 px wide) is shrunk to its box's
   size rounded (``cv2.INTER_AREA``), then warped onto the box (bilinear; its alpha the same
   way) — exact: the plate's pixel edges land on frame pixel edges ``[x, x + w)``.
2. The clip's light: the plate's grey levels are scaled by :func:`light_gains` (its white near the
   brightest parts of the car, following the frame's exposure); a grey clip gets a grey plate.
3. The clip's blur and noise: the warped plate and its alpha are blurred with a Gaussian of
   ``blur`` px, then blended, and the plate's pixels get Gaussian noise of ``noise`` grey levels.

The ground truth (``groundtruth_rect.txt``, 0-based ``x,y,w,h``, pixel-edge convention as OTB's)
is the plate's box; ``composite.json`` records the source and the parameters.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

from vistrack.io.video import VideoWriter
from vistrack.models.plate.layout import LAYOUTS

from .perturb import read_clip
from .plate_clip import render_plate
from .scene import atomic_clip

__all__ = ["composite_plate_clip", "plate_boxes", "light_gains", "composite_frame"]


def plate_boxes(car, *, aspect, width=0.4, centre=(0.53, 0.55), smooth=5):
    """The plate's boxes ``(T, 4)`` ``(x, y, w, h)`` on the car boxes ``car (T, 4)`` (module docstring)."""
    car = np.asarray(car, float)
    k = 2 * int(smooth) + 1
    pad = np.pad(car, ((smooth, smooth), (0, 0)), mode="edge")
    sm = np.stack([np.convolve(pad[:, j], np.ones(k) / k, mode="valid") for j in range(4)], axis=1)
    pw = width * sm[:, 2]
    ph = pw / aspect
    cx = sm[:, 0] + centre[0] * sm[:, 2]
    cy = sm[:, 1] + centre[1] * sm[:, 3]
    return np.stack([cx - pw / 2, cy - ph / 2, pw, ph], axis=1)


def light_gains(frames, car, exposure=False):
    """The plate's gain per frame (module docstring, step 2): ``0.95 P99 / 235`` with ``P99`` the
    median over the clip of the 99th grey-level percentile inside the car box; with ``exposure``,
    times each frame's mean grey level over the clip's median of it. car4's exposure is steady
    (``P99`` 251–254 from frame 5 on) while its mean grey level rises 124 -> 141 with the scene's
    content: followed, that made the plate 8 % darker in the first frame than later, and the
    learned grey-level histogram lost the plate (single-row, seed 1: AUC 0.27)."""
    p99, mean = [], []
    for f, (x, y, w, h) in zip(frames, np.asarray(car, float)):
        g = f if f.ndim == 2 else cv2.cvtColor(f, cv2.COLOR_BGR2GRAY)
        x0, y0 = int(max(0, x)), int(max(0, y))
        x1, y1 = int(min(g.shape[1], x + w)), int(min(g.shape[0], y + h))
        p99.append(np.percentile(g[y0:y1, x0:x1], 99) if x1 > x0 and y1 > y0 else np.nan)
        mean.append(g.mean())
    mean = np.array(mean)
    return 0.95 * np.nanmedian(p99) / 235.0 * (mean / np.median(mean) if exposure else np.ones(len(mean)))


def composite_frame(frame, plate, box, gain, rng, blur=0.7, noise=2.0):
    """``frame`` (BGR uint8) with ``plate`` (BGR float32) times ``gain`` composited at ``box (x, y, w,
    h)`` (module docstring, steps 1 and 3)."""
    h, w = frame.shape[:2]
    pw, ph = max(2, int(round(box[2]))), max(2, int(round(box[3])))
    sx, sy = box[2] / pw, box[3] / ph
    # pixel centres: plate pixel u (edge u + 1/2) lands on frame edge x + sx (u + 1/2), index that - 1/2
    m = np.array([[sx, 0, box[0] + 0.5 * sx - 0.5], [0, sy, box[1] + 0.5 * sy - 0.5]], np.float32)
    src = plate * np.float32(gain)
    is_grey = frame.ndim == 2 or (np.array_equal(frame[..., 0], frame[..., 1])
                                  and np.array_equal(frame[..., 1], frame[..., 2]))
    if is_grey:
        src = np.repeat(cv2.cvtColor(src, cv2.COLOR_BGR2GRAY)[..., None], 3, axis=2)
    small = cv2.resize(src, (pw, ph), interpolation=cv2.INTER_AREA)
    layer = cv2.warpAffine(small, m, (w, h), flags=cv2.INTER_LINEAR)
    alpha = cv2.warpAffine(np.ones((ph, pw), np.float32), m, (w, h), flags=cv2.INTER_LINEAR)
    if blur > 0:
        layer = cv2.GaussianBlur(layer, (0, 0), blur)
        alpha = cv2.GaussianBlur(alpha, (0, 0), blur)
    a = alpha[..., None]
    img = frame.astype(np.float32) if frame.ndim == 3 else np.repeat(frame[..., None], 3, axis=2).astype(np.float32)
    # the layer was premultiplied by the warp's coverage (zero outside the plate): blend as such
    out = img * (1 - a) + layer
    if noise > 0:
        n = rng.normal(0, noise, (h, w, 1)).astype(np.float32)
        out += n * a
    return np.clip(out, 0, 255).astype(np.uint8)


@atomic_clip
def composite_plate_clip(out, clip, *, layout="single-row", seed=0, width=0.4, centre=(0.53, 0.55), smooth=5,
                         blur=0.7, noise=2.0, upscale=1.0):
    """Write ``clip`` (a folder or video with box ground truth of a car) with a rendered ``layout``
    plate composited onto the car into the folder ``out``: ``<name>_plate.mp4``,
    ``groundtruth_rect.txt`` (the plate's boxes) and ``composite.json``. With ``upscale > 1`` the
    frames are first enlarged by it (bicubic; boxes scale with them, pixel edges to pixel edges): a
    single-row plate 0.4 of car4's car wide is 9 px high at the clip's 360x240. Returns the frame
    count."""
    src = Path(clip)
    video, car = read_clip(src)
    car = np.asarray(car, float) * upscale
    lay = LAYOUTS[layout]
    rng = np.random.default_rng(seed)
    plate = render_plate(lay, rng, 240)
    boxes = plate_boxes(car, aspect=lay.aspect, width=width, centre=centre, smooth=smooth)
    name = (src if src.is_dir() else src.parent).name
    frames = [f for t, f in video if t < len(boxes)]
    if upscale != 1.0:
        frames = [cv2.resize(f, None, fx=upscale, fy=upscale, interpolation=cv2.INTER_CUBIC) for f in frames]
    gains = light_gains(frames, car)
    out.mkdir(parents=True)
    writer, n = None, 0
    try:
        for t, frame in enumerate(frames):
            img = composite_frame(frame, plate, boxes[t], gains[t], rng, blur, noise)
            if writer is None:
                writer = VideoWriter(out / f"{name}_plate.mp4", video.fps or 30.0, (img.shape[1], img.shape[0]),
                                     codec="auto")
            writer.write(img)
            n += 1
    finally:
        if writer is not None:
            writer.close()
    np.savetxt(out / "groundtruth_rect.txt", boxes[:n], fmt="%.3f", delimiter=",")
    meta = {"source": str(src.resolve()), "video": f"{name}_plate.mp4", "layout": layout, "seed": seed, "width": width,
            "centre": list(centre), "smooth": smooth, "blur": blur, "noise": noise, "upscale": upscale}
    (out / "composite.json").write_text(json.dumps(meta, indent=2) + "\n")
    return n
