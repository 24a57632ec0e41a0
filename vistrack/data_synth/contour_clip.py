"""Synthetic contour clips with exact ground truth (for thesis 001 §1.3.1, §3.2.5, §4.3).

An object with a smooth closed outline (a closed cubic B-spline through ``n``
support points: hand-like or head-like), filled with its own texture, moves
over a static background full of edges:

- centre: AR(2) (velocity ``v_t = 0.9 v_{t-1} + N(0, (0.005 W)²)``), bouncing
  off the frame margins, with sudden jumps (probability 0.02 per frame,
  2.5–4.5 % of the frame width, by default);
- scale: ``log s`` AR(1) about 0 (std ~0.1); rotation: damped angular velocity,
  kept within ±45°;
- global and sweeping illumination change, motion blur along the motion
  (exposure half the frame interval),
  Gaussian sensor noise;
- optionally an identical distractor lying still in the scene (thesis §3.2.5);
- optionally (``color``) a distinctive saturated colour for the object (and the distractor).

Ground truth per frame: ``frame, visible, cx, cy, w, h, angle_deg, scale`` and
the support points ``qx0..qx{n-1}, qy0..qy{n-1}``. ``cx, cy`` is the mean of the
support points (the pose centre of :class:`vistrack.models.contour.model.Contour`);
``w, h`` the bounding box of the outline.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from vistrack.io.video import VideoWriter
from vistrack.models.contour.model import BSpline

from .scene import add_noise, atomic_clip, clutter_background, lighting, motion_blur, smooth_noise, write_clip_files

__all__ = ["contour_template", "make_contour_clip", "CLUTTER", "SHAPES"]

#: background shapes and sensor noise per clutter level
CLUTTER = {"low": (30, 3.0), "high": (140, 6.0)}
#: the outlines :func:`contour_template` draws
SHAPES = ("hand", "head")


def contour_template(kind, radius, n=24):
    """Support points ``(n, 2)`` of a hand-like or head-like outline of about ``radius`` px, centred."""
    phi = 2 * np.pi * np.arange(n) / n
    if kind == "hand":
        # a palm with four finger lobes on top and a thumb lobe at the side
        r = 1.0 + 0.32 * np.clip(np.cos(4 * (phi + np.pi / 2)), 0, None) * (np.sin(phi) < -0.2)
        r = r + 0.25 * np.exp(-((phi - 0.2) ** 2) / 0.05)
        r = 0.85 * r
    elif kind == "head":
        # head-and-shoulders: round top, wider bottom
        r = 1.0 + 0.18 * np.cos(2 * phi) * (np.sin(phi) > 0) + 0.1 * np.sin(phi)
    else:
        raise ValueError(f"unknown contour shape {kind!r}; choose {' or '.join(SHAPES)}")
    q = np.stack([radius * r * np.cos(phi), radius * r * np.sin(phi)], axis=1)
    return q - q.mean(axis=0)


def _object_sprite(template, rng, pad=1.35, color=False):
    """Texture and alpha mask of the object in template coordinates (origin at the sprite centre);
    ``color``: a saturated colour of random hue instead of a dark or bright grey-ish one."""
    spline = BSpline(len(template))
    outline = spline.dense(16) @ template
    half = int(np.ceil(np.max(np.abs(outline)) * pad))
    side = 2 * half + 1
    tex = np.stack([smooth_noise((side, side), rng, 6) for _ in range(3)], axis=-1)
    # a colour well apart from the background's mid-grey: clearly darker or brighter
    level = rng.uniform(30, 60) if rng.random() < 0.5 else rng.uniform(190, 225)
    base = (level + rng.uniform(-25, 25, 3)).astype(np.float32)
    if color:  # a distinctive colour (thesis §3.2.5: the colour-blob proposal's target)
        hsv = np.array([[[rng.uniform(0, 180), rng.uniform(190, 240), rng.uniform(170, 220)]]], np.uint8)
        base = cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0].astype(np.float32)
    sprite = np.clip(base + 30 * (tex - 0.5), 0, 255).astype(np.float32)
    mask = np.zeros((side * 4, side * 4), np.uint8)
    pts = np.round((outline + half + 0.5) * 4 - 0.5).astype(np.int32)
    cv2.fillPoly(mask, [pts], 255, cv2.LINE_AA)
    mask = cv2.resize(mask, (side, side), interpolation=cv2.INTER_AREA).astype(np.float32) / 255.0
    return sprite, mask, half


def _paste(frame, sprite, mask, half, cx, cy, scale, angle_deg, velocity=(0.0, 0.0)):
    """Composite the sprite onto ``frame`` at pose ``(cx, cy, scale, angle)`` with motion blur."""
    h, w = frame.shape[:2]
    th = np.deg2rad(angle_deg)
    c, s = scale * np.cos(th), scale * np.sin(th)
    m = np.array([[c, -s, cx - (c * half - s * half)], [s, c, cy - (s * half + c * half)]], np.float32)
    obj = cv2.warpAffine(sprite, m, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    alpha = cv2.warpAffine(mask, m, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    obj = motion_blur(obj * alpha[..., None], velocity)
    alpha = motion_blur(alpha, velocity)
    frame *= 1.0 - alpha[..., None]
    frame += obj


def _motion(rng, pos, ang, frames, size, margin, jump_prob, jump_size):
    """The object's pose per frame: ``(pos, scale, angle_deg, blur_v)`` for ``t = 0..frames-1``,
    ``blur_v`` the motion blur's vector (the exposure is half the frame time). The draws for frame
    ``t`` are taken from ``rng`` when the caller asks for that frame (the renderer's noise follows)."""
    w, h = size
    vel = np.zeros(2)
    log_s, omega = 0.0, 0.0
    for t in range(frames):
        blur_v = np.zeros(2)
        if t > 0:
            vel = 0.9 * vel + rng.normal(0, 0.005 * w, 2)
            step = vel.copy()
            if rng.random() < jump_prob:  # a sudden movement
                a = rng.uniform(0, 2 * np.pi)
                step += rng.uniform(*jump_size) * w * np.array([np.cos(a), np.sin(a)])
            pos = pos + step
            for k, lim in enumerate((w, h)):
                if pos[k] < margin or pos[k] > lim - margin:
                    pos[k] = np.clip(pos[k], margin, lim - margin)
                    vel[k] = -vel[k]
            log_s = 0.97 * log_s + rng.normal(0, 0.02)
            omega = 0.9 * omega + rng.normal(0, 0.6)
            ang += omega
            if abs(ang) > 45:
                ang, omega = float(np.clip(ang, -45, 45)), -omega
            blur_v = 0.5 * step
        yield pos, float(np.exp(log_s)), ang, blur_v


def _truth_row(t, template, dense, pos, scale, ang):
    """One ``groundtruth.csv`` row: the pose, the outline's bounding box and the support points."""
    th = np.deg2rad(ang)
    rot = scale * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    q = template @ rot.T + pos
    outline = dense @ q
    lo, hi = outline.min(axis=0), outline.max(axis=0)
    row = {"frame": t, "visible": 1, "cx": pos[0], "cy": pos[1], "w": hi[0] - lo[0], "h": hi[1] - lo[1],
           "angle_deg": ang, "scale": scale}
    row.update({f"qx{i}": q[i, 0] for i in range(len(q))})
    row.update({f"qy{i}": q[i, 1] for i in range(len(q))})
    return row


def _contour_meta(frames, w, h, fps, seed, clutter, shape, color, template, distractor_pose, jump_prob, jump_size):
    """``meta.json`` of a contour clip."""
    shapes, noise = CLUTTER[clutter]
    return {
        "kind": "contour",
        "model": "contour",
        "frames": frames,
        "size": [w, h],
        "fps": fps,
        "seed": seed,
        "clutter": clutter,
        "shape": shape,
        "color": bool(color),
        "template": {"support_points": np.round(template, 4).tolist(),
                     "note": "support points at scale 1, angle 0, centred; pose (cx, cy, scale, angle_deg)"},
        "distractor": distractor_pose,
        "dynamics": {"velocity_ar": 0.9, "velocity_noise_px": 0.005 * w, "jump_prob": jump_prob,
                     "jump_px": [jump_size[0] * w, jump_size[1] * w], "log_scale_ar": 0.97, "log_scale_noise": 0.02,
                     "angle_rate_ar": 0.9, "angle_rate_noise_deg": 0.6, "max_angle_deg": 45},
        "noise_std": noise,
        "background_shapes": shapes,
    }


@atomic_clip
def make_contour_clip(out, *, frames=300, size=(320, 240), seed=0, clutter="high", distractor=True,
                      shape="hand", n_support=24, fps=30.0, jump_prob=0.02, jump_size=(0.025, 0.045),
                      color=False, model="contour", progress=None):
    """Render a contour clip into folder ``out`` (video.mp4, groundtruth.csv, meta.json).

    ``model``: the model ``meta.json`` names, which ``run`` and ``eval`` track the clip with when
    no ``--model`` is given (``vistrack demo``'s clip names the box model it tracked it with).

    ``jump_prob``: the chance of a sudden jump per frame; ``jump_size``: its length range as
    shares of the frame width. ``color``: the object (and the distractor, identical) has a
    distinctive saturated colour, the set-up of the colour-blob proposal of thesis §3.2.5.
    Returns the meta dictionary. ``progress(k)`` is called after every frame when given.
    """
    if clutter not in CLUTTER:
        raise ValueError(f"clutter must be one of {', '.join(CLUTTER)}, got {clutter!r}")
    if frames < 1:
        raise ValueError(f"need at least one frame, got {frames}")
    w, h = int(size[0]), int(size[1])
    if w < 64 or h < 48:
        raise ValueError(f"frame size {w}x{h} is too small (need at least 64x48)")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    radius = 0.13 * min(w, h)
    template = contour_template(shape, radius, n_support)
    shapes, noise = CLUTTER[clutter]
    bg = clutter_background((w, h), rng, int(shapes * w * h / (320 * 240)))
    sprite, mask, half = _object_sprite(template, rng, color=color)
    margin = 1.2 * radius
    pos = np.array([rng.uniform(0.3, 0.7) * w, rng.uniform(0.3, 0.7) * h])
    ang = float(rng.uniform(-15, 15))
    distractor_pose = None
    if distractor:
        for _ in range(100):  # lie still somewhere away from the start
            d = np.array([rng.uniform(margin, w - margin), rng.uniform(margin, h - margin)])
            if np.linalg.norm(d - pos) > 3 * radius:
                break
        distractor_pose = {"cx": float(d[0]), "cy": float(d[1]), "scale": 1.0, "angle_deg": float(rng.uniform(-30, 30))}
    phase = rng.uniform(0, 2 * np.pi)
    dense = BSpline(n_support).dense(8)
    cols = ["frame", "visible", "cx", "cy", "w", "h", "angle_deg", "scale"]
    cols += [f"qx{i}" for i in range(n_support)] + [f"qy{i}" for i in range(n_support)]
    rows = []
    motion = _motion(rng, pos, ang, frames, (w, h), margin, jump_prob, jump_size)
    with VideoWriter(out / "video.mp4", fps, (w, h)) as vw:
        for t, (pos, scale, ang, blur_v) in enumerate(motion):
            frame = bg * lighting((w, h), t, phase)
            if distractor_pose:
                _paste(frame, sprite, mask, half, distractor_pose["cx"], distractor_pose["cy"], 1.0,
                       distractor_pose["angle_deg"])
            _paste(frame, sprite, mask, half, pos[0], pos[1], scale, ang, blur_v)
            vw.write(add_noise(frame, rng, noise))
            rows.append(_truth_row(t, template, dense, pos, scale, ang))
            if progress:
                progress(1)
    meta = _contour_meta(frames, w, h, fps, seed, clutter, shape, color, template, distractor_pose, jump_prob,
                         jump_size)
    meta["model"] = model
    write_clip_files(out, rows, cols, meta)
    return meta
