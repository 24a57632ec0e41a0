"""Synthetic road clips with license plates and exact ground truth (thesis 001 §1.3.2, §4.5.3).

Cars (rendered bodies with windows, a grille, lights and a plate) drive into
the frame from one side and leave at the other, growing as they approach and
with a slowly changing shear angle of the plate; by default one car is in
view at a time, with stretches without any plate. The scene has buildings,
signs with text and grilles (plate-like clutter), illumination change, motion
blur on the moving car and sensor noise.

Plates follow a :class:`~vistrack.models.plate_layout.PlateLayout`: the
Japanese layout of Fig. 1.5 (white, bordered, a top row of small characters,
a small glyph at the left and four large digits) or a single-row layout.

Ground truth per frame (``groundtruth.csv``): ``frame, visible, id, cx, cy, w, h,
angle_deg, scale`` and the vertices ``x0, y0, ..., x3, y3`` (top-left,
top-right, bottom-right, bottom-left) of the plate in view (``visible = 1``
when the whole plate is inside the frame; NaN geometry when none is).
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from vistrack.models.plate_layout import LAYOUTS, plate_vertices
from vistrack.video import VideoWriter

from .render import add_noise, atomic_clip, lighting, motion_blur, smooth_noise, write_clip_files

__all__ = ["render_plate", "make_plate_clip"]

_FONT = cv2.FONT_HERSHEY_SIMPLEX
_FONT_BOLD = cv2.FONT_HERSHEY_DUPLEX


def _put_text_in(img, text, box, font, color, thickness):
    """Draw ``text`` scaled to fill ``box = (x0, y0, x1, y1)`` (pixels)."""
    x0, y0, x1, y1 = box
    (tw, th), base = cv2.getTextSize(text, font, 1.0, thickness)
    scale = min((x1 - x0) / tw, (y1 - y0) / (th + base * 0.3))
    (tw, th), base = cv2.getTextSize(text, font, scale, thickness)
    org = (int(x0 + (x1 - x0 - tw) / 2), int(y1 - (y1 - y0 - th) / 2))
    cv2.putText(img, text, org, font, scale, color, thickness, cv2.LINE_AA)


def render_plate(layout, rng, width=240):
    """A plate image (BGR float32, ``width × width/aspect``) for ``layout`` with random characters."""
    h = int(round(width / layout.aspect))
    img = np.full((h, width, 3), 235, np.uint8)  # cv2.putText draws on 8-bit images only
    ink = (30, 70, 20) if layout.name == "jp" else (20, 20, 20)
    t = max(2, width // 80)
    cv2.rectangle(img, (t // 2, t // 2), (width - 1 - t // 2, h - 1 - t // 2), ink, t)
    digits = "".join(str(d) for d in rng.integers(0, 10, 4))

    def px(box):
        return (box[0] * width, box[1] * h, box[2] * width, box[3] * h)

    if layout.name == "jp":
        letters = "".join(chr(c) for c in rng.integers(65, 91, 3))
        _put_text_in(img, f"{letters} {rng.integers(100, 999)}", px(layout.small[0]), _FONT, ink, max(1, width // 120))
        _put_text_in(img, chr(int(rng.integers(97, 123))), px(layout.small[1]), _FONT, ink, max(1, width // 100))
        _put_text_in(img, f"{digits[:2]}-{digits[2:]}", px(layout.big[0]), _FONT_BOLD, ink, max(2, width // 40))
    else:
        letters = "".join(chr(c) for c in rng.integers(65, 91, 2))
        _put_text_in(img, "EU", px(layout.small[0]), _FONT, (160, 60, 20), max(1, width // 200))
        _put_text_in(img, f"{letters} {digits}", px(layout.big[0]), _FONT_BOLD, ink, max(2, width // 90))
    return img.astype(np.float32)


def _background(size, rng, signs=6):
    """Road scene: sky, buildings with windows, road with lane marks, signs with text, grilles."""
    w, h = size
    img = np.zeros((h, w, 3), np.uint8)
    horizon = int(h * 0.42)
    img[:horizon] = (200, 170, 140)
    img[horizon:] = (95, 95, 100)
    x = 0
    while x < w:  # buildings
        bw = int(rng.uniform(0.08, 0.2) * w)
        bh = int(rng.uniform(0.15, 0.35) * h)
        col = tuple(int(c) for c in rng.uniform(70, 190, 3))
        cv2.rectangle(img, (x, horizon - bh), (x + bw, horizon), col, -1)
        for wy in range(horizon - bh + 6, horizon - 8, 14):
            for wx in range(x + 5, x + bw - 8, 12):
                cv2.rectangle(img, (wx, wy), (wx + 6, wy + 7), (60, 60, 70), -1)
        x += bw + int(rng.uniform(0, 0.03) * w)
    for k in range(8):  # lane marks
        lx = int((k + 0.5) * w / 8)
        cv2.rectangle(img, (lx, int(h * 0.93)), (lx + w // 20, int(h * 0.95)), (220, 220, 220), -1)
    for _ in range(signs):  # plate-like clutter: text signs and grilles
        sw = int(rng.uniform(0.06, 0.14) * w)
        sh = int(sw / rng.uniform(1.5, 3.5))
        sx, sy = int(rng.uniform(0, w - sw)), int(rng.uniform(0.05 * h, horizon - sh))
        if rng.random() < 0.6:
            cv2.rectangle(img, (sx, sy), (sx + sw, sy + sh), (230, 230, 230), -1)
            cv2.rectangle(img, (sx, sy), (sx + sw, sy + sh), (40, 40, 40), 1)
            _put_text_in(img, "".join(chr(c) for c in rng.integers(65, 91, 4)),
                         (sx + 3, sy + 3, sx + sw - 3, sy + sh - 3), _FONT, (30, 30, 30), 1)
        else:
            for gy in range(sy, sy + sh, 4):
                cv2.line(img, (sx, gy), (sx + sw, gy), (40, 40, 40), 2)
    tex = smooth_noise((h, w), rng, 6)[..., None]
    return img.astype(np.float32) + 20 * (tex - 0.5)


def _car_sprite(plate, rng):
    """Car body around the plate: BGR float32 image, alpha and the plate's position in it."""
    ph, pw = plate.shape[:2]
    cw, ch = int(pw * 4.2), int(pw * 2.1)
    img = np.zeros((ch, cw, 3), np.float32)
    alpha = np.zeros((ch, cw), np.float32)
    body = tuple(float(c) for c in rng.uniform(30, 220, 3))
    cv2.rectangle(img, (0, int(ch * 0.35)), (cw - 1, ch - 1), body, -1)
    cv2.rectangle(alpha, (0, int(ch * 0.35)), (cw - 1, ch - 1), 1.0, -1)
    roof = np.array([[int(cw * 0.15), int(ch * 0.36)], [int(cw * 0.3), 0], [int(cw * 0.7), 0],
                     [int(cw * 0.85), int(ch * 0.36)]], np.int32)
    cv2.fillPoly(img, [roof], body)
    cv2.fillPoly(alpha, [roof], 1.0)
    win = np.array([[int(cw * 0.2), int(ch * 0.33)], [int(cw * 0.32), int(ch * 0.05)], [int(cw * 0.68), int(ch * 0.05)],
                    [int(cw * 0.8), int(ch * 0.33)]], np.int32)
    cv2.fillPoly(img, [win], (70.0, 60.0, 50.0))
    for gy in range(int(ch * 0.45), int(ch * 0.58), max(3, ch // 40)):  # grille above the plate
        cv2.line(img, (int(cw * 0.3), gy), (int(cw * 0.7), gy), (25.0, 25.0, 25.0), max(1, ch // 80))
    for lx in (int(cw * 0.05), int(cw * 0.8)):  # lights
        cv2.rectangle(img, (lx, int(ch * 0.45)), (lx + int(cw * 0.15), int(ch * 0.58)), (200.0, 230.0, 240.0), -1)
    px0, py0 = (cw - pw) // 2, int(ch * 0.66)
    img[py0:py0 + ph, px0:px0 + pw] = plate
    return img, alpha, (px0, py0)


@atomic_clip
def make_plate_clip(out, *, frames=300, size=(640, 480), seed=0, cars=3, layout="jp", overlap=False, fps=30.0,
                    progress=None):
    """Render a road clip into ``out`` (video.mp4, groundtruth.csv, meta.json); returns the meta dict."""
    if layout not in LAYOUTS:
        raise ValueError(f"layout must be one of {', '.join(LAYOUTS)}, got {layout!r}")
    if frames < 1 or cars < 1:
        raise ValueError("need at least one frame and one car")
    w, h = int(size[0]), int(size[1])
    if w < 160 or h < 120:
        raise ValueError(f"frame size {w}x{h} is too small for plates (at least 160x120)")
    lay = LAYOUTS[layout]
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    bg = _background((w, h), rng)
    # schedule: each car crosses in `span` frames; cars follow one another with a gap (or overlap)
    span = max(20, int(frames / cars * (1.4 if overlap else 0.75)))
    starts = np.linspace(0, max(0, frames - span), cars).astype(int) if cars > 1 else np.array([0])
    car_list = []
    for k, t0 in enumerate(starts):
        plate = render_plate(lay, rng, 240)
        sprite, alpha, (px0, py0) = _car_sprite(plate, rng)
        direction = 1 if rng.random() < 0.5 else -1
        s0, s1 = rng.uniform(0.09, 0.12) * w, rng.uniform(0.13, 0.17) * w  # plate width px, approaching
        y0, y1 = rng.uniform(0.6, 0.68) * h, rng.uniform(0.7, 0.78) * h
        th0, th1 = np.deg2rad(rng.uniform(-8, 8, 2))
        car_list.append(dict(id=k, t0=int(t0), span=span, sprite=sprite, alpha=alpha, plate_xy=(px0, py0),
                             plate_w=plate.shape[1], dir=direction, s=(s0, s1), y=(y0, y1), th=(th0, th1)))
    phase = rng.uniform(0, 2 * np.pi)
    cols = ["frame", "visible", "id", "cx", "cy", "w", "h", "angle_deg", "scale"]
    cols += [f"{c}{i}" for i in range(4) for c in "xy"]
    rows = []
    with VideoWriter(out / "video.mp4", fps, (w, h)) as vw:
        for t in range(frames):
            frame = bg * lighting((w, h), t, phase, amplitude=0.2)
            best = None
            for car in car_list:
                f = (t - car["t0"]) / car["span"]
                if not 0.0 <= f <= 1.0:
                    continue
                s = car["s"][0] + f * (car["s"][1] - car["s"][0])
                scale = s / car["plate_w"]  # sprite px -> image px
                cw = car["sprite"].shape[1] * scale
                x_c = -cw / 2 + f * (w + cw)  # plate centre x crosses the frame
                if car["dir"] < 0:
                    x_c = w - x_c
                y_c = car["y"][0] + f * (car["y"][1] - car["y"][0])
                th = car["th"][0] + f * (car["th"][1] - car["th"][0])
                pose = np.array([x_c, y_c, th, s])
                # affine: sprite -> image, plate centre to (x_c, y_c), shear tan(th) on x
                px0, py0 = car["plate_xy"]
                pcx, pcy = px0 + car["plate_w"] / 2, py0 + car["plate_w"] / lay.aspect / 2
                m = np.array([[scale, 0, x_c - scale * pcx],
                              [scale * np.tan(th), scale, y_c - scale * (pcy + np.tan(th) * pcx)]], np.float32)
                obj = cv2.warpAffine(car["sprite"], m, (w, h), flags=cv2.INTER_LINEAR)
                al = cv2.warpAffine(car["alpha"], m, (w, h), flags=cv2.INTER_LINEAR)
                v = car["dir"] * (w + cw) / car["span"]
                obj = motion_blur(obj * al[..., None], (0.5 * v, 0.0))
                al = motion_blur(al, (0.5 * v, 0.0))
                frame *= 1.0 - al[..., None]
                frame += obj
                verts = plate_vertices(pose, lay.aspect)[0]
                inside = np.all((verts[:, 0] >= 0) & (verts[:, 0] <= w - 1) & (verts[:, 1] >= 0) & (verts[:, 1] <= h - 1))
                if inside and (best is None or s > best[1][3]):
                    best = (car["id"], pose, verts)
            vw.write(add_noise(frame, rng, 4.0))
            if best is None:
                row = {c: np.nan for c in cols}
                row.update(frame=t, visible=0, id=-1)
            else:
                cid, pose, verts = best
                lo, hi = verts.min(axis=0), verts.max(axis=0)
                row = {"frame": t, "visible": 1, "id": cid, "cx": pose[0], "cy": pose[1], "w": hi[0] - lo[0],
                       "h": hi[1] - lo[1], "angle_deg": np.rad2deg(pose[2]), "scale": pose[3]}
                for i in range(4):
                    row[f"x{i}"], row[f"y{i}"] = verts[i]
            rows.append(row)
            if progress:
                progress(1)
    meta = {"kind": "plate", "model": "plate", "frames": frames, "size": [w, h], "fps": fps, "seed": seed,
            "cars": cars, "layout": layout, "aspect": lay.aspect, "overlap": overlap,
            "note": "scale = plate width in px; angle_deg = angle of the non-vertical sides; vertices TL, TR, BR, BL"}
    write_clip_files(out, rows, cols, meta)
    return meta
