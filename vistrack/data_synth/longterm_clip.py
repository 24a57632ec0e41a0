"""Synthetic long-term clips: an object that leaves the frame and hides behind a pillar, and comes back
elsewhere, with exact ground truth that marks it absent (issue 44; for a tracker's ``visible`` and
VOT-LT's long-term scores, :func:`vistrack.scoring.metrics.lt_scores`).

Scene
    a static background with some edges (:func:`~vistrack.data_synth.scene.clutter_background`, 10
    shapes per 320 × 240 px), a
    full-height opaque pillar (vertical stripes of its own colours) right of the middle, global and
    sweeping illumination change and sensor noise, as the other synthetic clips.
Object
    an ellipse of about 15 % of the frame's shorter side in a saturated colour of random hue (seeded),
    with dark stripes across it and some texture, drawn with motion blur along its motion.
Script (speeds in px per frame at 30 frames/s; ``gap`` seconds of absence, 2 by default)
    1. it wanders about a point in the left third (a smooth random path) for 2 s;
    2. it leaves through the top or bottom edge (seeded) at 5 px/frame and stays out of view for
       ``gap`` seconds;
    3. it comes back through the left edge at a random height and wanders about a new point for 1.7 s;
    4. it moves right behind the pillar, stays hidden there for ``gap`` seconds (the pillar covers it
       whole), and comes out on the pillar's right side, where it wanders to the end (1.5 s).
Ground truth (``groundtruth.csv``)
    ``frame, visible, cx, cy, w, h, angle_deg, scale``: ``visible = 0`` and ``0, 0, 0, 0`` where no pixel
    of the object is in view (outside the frame, or wholly behind the pillar); elsewhere its box,
    clipped to the frame (the pillar does not cut it: an occluded object keeps its box, as annotators
    draw it). ``meta.json`` lists the absences as ``[first, last]`` frames.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from vistrack.io.video import VideoWriter

from .scene import add_noise, atomic_clip, clutter_background, lighting, motion_blur, smooth_noise, write_clip_files

__all__ = ["make_longterm_clip", "SPEED"]

#: the object's speed when it leaves, comes back and goes behind the pillar (px per frame)
SPEED = 5.0
COLUMNS = ["frame", "visible", "cx", "cy", "w", "h", "angle_deg", "scale"]


def _sprite(rng, w, h):
    """Texture ``(H, W, 3) float32`` and alpha ``(H, W) float32`` of the object: an ellipse in a saturated
    colour with dark stripes across it (a random angle and pitch) and some texture."""
    hsv = np.array([[[rng.uniform(0, 180), rng.uniform(170, 230), rng.uniform(170, 230)]]], np.uint8)
    base = cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0].astype(np.float32)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    a, pitch = rng.uniform(0, np.pi), rng.uniform(0.35, 0.5) * min(w, h)
    stripes = (np.cos(2 * np.pi * (xx * np.cos(a) + yy * np.sin(a)) / pitch) > 0.3)[..., None]
    tex = np.stack([smooth_noise((h, w), rng, 5) for _ in range(3)], axis=-1)
    sprite = np.clip(np.where(stripes, 0.25 * base, base) + 40 * (tex - 0.5), 0, 255).astype(np.float32)
    mask = np.zeros((4 * h, 4 * w), np.uint8)
    cv2.ellipse(mask, (2 * w, 2 * h), (2 * w - 2, 2 * h - 2), 0, 0, 360, 255, -1, cv2.LINE_AA)
    alpha = cv2.resize(mask, (w, h), interpolation=cv2.INTER_AREA).astype(np.float32) / 255.0
    return sprite, alpha


def _wander(rng, centre, frames, amplitude):
    """``frames`` positions ``(frames, 2)`` on a smooth random path about ``centre`` (two sinusoids per axis
    of random periods and phases), starting at ``centre``."""
    t = np.arange(frames)[:, None]
    out = np.zeros((frames, 2))
    for k in range(2):
        periods, phases = rng.uniform(40, 90, 2), rng.uniform(0, 2 * np.pi, 2)
        wave = np.sin(2 * np.pi * t / periods + phases).sum(axis=1) - np.sin(phases).sum()
        out[:, k] = centre[k] + 0.5 * amplitude * wave
    return out


def _line(a, b, speed=SPEED):
    """Positions from ``a`` towards ``b`` (``b`` included) at ``speed`` px per frame ``(n, 2)``."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    n = max(1, int(np.ceil(np.linalg.norm(b - a) / speed)))
    return a + (b - a) * (np.arange(1, n + 1) / n)[:, None]


def script(rng, size, obj, pillar, gap, fps=30.0):
    """The object's centre per frame ``(T, 2)`` (module docstring): wander, leave through the top or bottom,
    away ``gap`` s, back through the left edge, wander, behind the pillar ``(x0, x1)`` for ``gap`` s, out
    on its right, wander."""
    w, h = size
    ow, oh = obj
    x0, x1 = pillar
    g = int(round(gap * fps))
    a1 = np.array([0.22 * w, rng.uniform(0.4, 0.6) * h])
    path = [_wander(rng, a1, int(2 * fps), 0.12 * min(w, h))]
    up = rng.random() < 0.5
    out_y = -oh if up else h + oh
    path.append(_line(path[-1][-1], (path[-1][-1][0] + rng.uniform(-0.1, 0.1) * w, out_y)))
    path.append(np.repeat(path[-1][-1:], g, axis=0))  # out of view
    back = np.array([-ow, rng.uniform(0.3, 0.7) * h])
    a2 = np.array([0.25 * w, rng.uniform(0.35, 0.65) * h])
    path.append(np.array([back]))
    path.append(_line(back, a2))
    path.append(_wander(rng, a2, int(1.7 * fps), 0.1 * min(w, h)))
    hide = np.array([(x0 + x1) / 2, path[-1][-1][1]])
    path.append(_line(path[-1][-1], hide))
    path.append(hide + np.cumsum(rng.normal(0, 0.3, (g, 2)), axis=0) * [0.0, 1.0])  # hidden: a slow drift in y
    a3 = np.array([x1 + 0.6 * (w - x1), path[-1][-1][1]])
    path.append(_line(path[-1][-1], a3))
    path.append(_wander(rng, a3, int(1.5 * fps), 0.06 * min(w, h)))
    return np.concatenate(path)


def _pillar_image(rng, h, width):
    """The pillar's pixels ``(h, width, 3) float32``: vertical stripes in two muted colours with some texture."""
    cols = rng.uniform(40, 140, (2, 3)).astype(np.float32)
    x = np.arange(width)
    stripe = ((x // max(4, width // 9)) % 2)[None, :, None]
    img = np.where(stripe == 0, cols[0], cols[1]) * np.ones((h, 1, 1), np.float32)
    return img + 25 * (np.stack([smooth_noise((h, width), rng, 12) for _ in range(3)], axis=-1) - 0.5)


@atomic_clip
def make_longterm_clip(out, *, size=(640, 480), seed=0, gap=2.0, fps=30.0, progress=None, on_length=None):
    """Render a long-term clip into folder ``out`` (video.mp4, groundtruth.csv, meta.json; module
    docstring). ``gap``: the seconds of each absence. Returns the meta dictionary; ``on_length(n)`` is told the
    clip's length once its script is drawn and ``progress(k)`` is called after every frame, when given."""
    w, h = int(size[0]), int(size[1])
    if w < 160 or h < 120:
        raise ValueError(f"frame size {w}x{h} is too small for a long-term clip (at least 160x120)")
    if not 0.2 <= gap <= 60:
        raise ValueError(f"the absence must last 0.2 to 60 seconds, got {gap}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    bg = clutter_background((w, h), rng, int(10 * w * h / (320 * 240)))
    side = 0.15 * min(w, h)
    ow, oh = 2 * int(round(0.45 * side)), 2 * int(round(0.55 * side))  # even sides: the centre on a pixel corner
    sprite, alpha = _sprite(rng, ow, oh)
    x0, x1 = int(round(0.52 * w)), int(round(0.52 * w)) + int(round(1.9 * ow))
    pillar = _pillar_image(rng, h, x1 - x0)
    centres = script(rng, (w, h), (ow, oh), (x0, x1), gap, fps)
    if on_length is not None:
        on_length(len(centres))
    phase = rng.uniform(0, 2 * np.pi)
    rows, absent, first = [], [], None
    with VideoWriter(out / "video.mp4", fps, (w, h)) as vw:
        for t, (cx, cy) in enumerate(centres):
            frame = bg * lighting((w, h), t, phase)
            layer, obj = np.zeros((h, w), np.float32), np.zeros((h, w, 3), np.float32)
            ox, oy = int(round(cx)) - ow // 2, int(round(cy)) - oh // 2
            a0, a1, b0, b1 = max(0, oy), min(h, oy + oh), max(0, ox), min(w, ox + ow)
            if a0 < a1 and b0 < b1:
                layer[a0:a1, b0:b1] = alpha[a0 - oy:a1 - oy, b0 - ox:b1 - ox]
                obj[a0:a1, b0:b1] = sprite[a0 - oy:a1 - oy, b0 - ox:b1 - ox]
            v = centres[t] - centres[t - 1] if t else np.zeros(2)
            obj, layer = motion_blur(obj * layer[..., None], 0.5 * v), motion_blur(layer, 0.5 * v)
            frame = frame * (1 - layer[..., None]) + obj
            frame[:, x0:x1] = pillar * lighting((w, h), t, phase)[:, x0:x1]
            vw.write(add_noise(frame, rng, 3.0))
            seen = layer.copy()
            seen[:, x0:x1] = 0.0
            if float(seen.max()) > 0.05:  # some of the object in view
                bx0, by0 = max(0.0, cx - ow / 2), max(0.0, cy - oh / 2)
                bx1, by1 = min(float(w), cx + ow / 2), min(float(h), cy + oh / 2)
                rows.append({"frame": t, "visible": 1, "cx": (bx0 + bx1) / 2, "cy": (by0 + by1) / 2, "w": bx1 - bx0,
                             "h": by1 - by0, "angle_deg": 0.0, "scale": 1.0})
                if first is not None:
                    absent.append([first, t - 1])
                    first = None
            else:
                rows.append({"frame": t, "visible": 0, "cx": 0.0, "cy": 0.0, "w": 0.0, "h": 0.0, "angle_deg": 0.0,
                             "scale": 1.0})
                first = t if first is None else first
            if progress:
                progress(1)
    if first is not None:
        absent.append([first, len(centres) - 1])
    meta = {"kind": "longterm", "model": "box", "frames": len(centres), "size": [w, h], "fps": fps, "seed": seed,
            "gap_s": gap, "object": {"w": ow, "h": oh}, "pillar": {"x0": x0, "x1": x1}, "absent": absent,
            "speed_px": SPEED, "noise_std": 3.0}
    write_clip_files(out, rows, COLUMNS, meta)
    return meta
