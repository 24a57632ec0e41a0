"""Synthetic road clips with license plates and exact ground truth (thesis 001 §1.3.2, §4.5.3).

Cars (rendered bodies with windows, a grille, lights and a plate) drive into
the frame from one side and leave at the other, growing as they approach and
with a slowly changing shear angle of the plate; by default one car is in
view at a time, with stretches without any plate. The scene has buildings,
signs with text and grilles (plate-like clutter), illumination change, motion
blur on the moving car and sensor noise.

Plates follow a :class:`~vistrack.models.plate.layout.PlateLayout`: the
Japanese layout of Fig. 1.5 (white, bordered, a top row of small characters,
a small glyph at the left and four large digits) or a single-row layout.

With ``overlap`` the cars (narrower: 3.4 plate widths) follow one another closely, in three
lanes in turn (farther lanes higher in the image, with smaller plates, drawn first), so that up
to three plates are in view at once (a fourth car may be coming in or going out at the border,
its plate not in view); a nearer car passing in front hides a plate.

Ground truth per frame (``groundtruth.csv``): ``frame, visible, id, cx, cy, w, h,
angle_deg, scale`` and the vertices ``x0, y0, ..., x3, y3`` (top-left,
top-right, bottom-right, bottom-left) of the plate in view — the largest when
there are several (``visible = 1``; empty geometry cells and ``id = -1`` when none is).
A plate is in view when the whole of it is inside the frame and at most
:data:`MAX_HIDDEN` (10 %) of it is hidden by a car in front.

Ground truth per plate (``objects.csv``, the multi-target truth): the same
columns plus ``hidden`` (the share of the plate hidden by cars in front), one
row per frame and plate in view, in order of frame and then of ``id`` (the
car's number, 0, 1, ... in order of entry, the same in every frame); a frame
with no plate in view has one row with ``visible = 0``, ``id = -1`` and empty
geometry cells, so every frame has at least one row.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from vistrack.io.clips import write_track_csv
from vistrack.io.video import VideoWriter
from vistrack.models.plate.layout import LAYOUTS, plate_vertices

from .scene import add_noise, atomic_clip, lighting, motion_blur, smooth_noise, write_clip_files

__all__ = ["render_plate", "make_plate_clip", "detection_frames"]

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


def _car_sprite(plate, rng, width=4.2):
    """Car body around the plate (``width`` plate widths wide): BGR float32 image, alpha and the
    plate's position in it."""
    ph, pw = plate.shape[:2]
    cw, ch = int(pw * width), int(pw * 2.1)
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


def _car(k, t0, span, lay, rng, w, h, lane=None):
    """One car of the schedule: its sprite, direction, and plate width, centre height and angle
    at its entry and exit (``lane``: 0 far .. 2 near, for ``overlap`` clips; ``None``: the
    single-car clips' draws)."""
    plate = render_plate(lay, rng, 240)
    # overlap clips: narrower cars (3.4 plate widths, as a 52-cm plate on a 1.8-m car), so three fit
    sprite, alpha, (px0, py0) = _car_sprite(plate, rng, 4.2 if lane is None else 3.4)
    direction = 1 if rng.random() < 0.5 else -1
    if lane is None:
        s0, s1 = rng.uniform(0.09, 0.12) * w, rng.uniform(0.13, 0.17) * w  # plate width px, approaching
        y0, y1 = rng.uniform(0.6, 0.68) * h, rng.uniform(0.7, 0.78) * h
    else:  # a lane further away is higher in the image and its plates smaller
        s0 = (0.085 + 0.02 * lane + rng.uniform(-0.005, 0.005)) * w
        y0 = (0.6 + 0.055 * lane + rng.uniform(-0.01, 0.01)) * h
        s1, y1 = s0 + 0.03 * w, y0 + 0.06 * h
    th0, th1 = np.deg2rad(rng.uniform(-8, 8, 2))
    return dict(id=k, t0=int(t0), span=span, sprite=sprite, alpha=alpha, plate_xy=(px0, py0), plate_w=plate.shape[1],
                dir=direction, s=(s0, s1), y=(y0, y1), th=(th0, th1), lane=lane)


def _schedule(frames, cars, overlap):
    """Entry frames and crossing time (frames) of the cars. One at a time: they follow one another
    with gaps. ``overlap``: evenly spread, each entering 0.27 of a crossing after the one before:
    a plate is wholly in view for the middle 2/3 of its car's crossing, so up to three plates are
    in view at once, never four (a fourth car may be coming in or going out at the border)."""
    if overlap:
        span = max(20, int(frames / (1 + (cars - 1) * OVERLAP_GAP)))
    else:
        span = max(20, int(frames / cars * 0.75))
    starts = np.linspace(0, max(0, frames - span), cars).astype(int) if cars > 1 else np.array([0])
    return starts, span


#: ``overlap`` clips: a car enters this share of a crossing after the one before it
OVERLAP_GAP = 0.27


def _place(car, t, w, h, aspect):
    """The car's plate pose ``(u, w, θ, s)`` at frame ``t``, the sprite -> image affine map and the
    sprite's horizontal speed (px/frame); ``None`` when the car is not on the road."""
    f = (t - car["t0"]) / car["span"]
    if not 0.0 <= f <= 1.0:
        return None
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
    pcx, pcy = px0 + car["plate_w"] / 2, py0 + car["plate_w"] / aspect / 2
    m = np.array([[scale, 0, x_c - scale * pcx],
                  [scale * np.tan(th), scale, y_c - scale * (pcy + np.tan(th) * pcx)]], np.float32)
    return pose, m, car["dir"] * (w + cw) / car["span"]


def _hidden(verts, covers, size):
    """The share of the plate ``verts (4, 2)`` hidden by ``covers`` (alpha maps of the cars drawn
    over it): the mean over the plate's pixels of ``1 - Π (1 - α)``."""
    if not covers:
        return 0.0
    w, h = size
    lo = np.clip(np.floor(verts.min(axis=0)).astype(int), 0, [w - 1, h - 1])
    hi = np.clip(np.ceil(verts.max(axis=0)).astype(int) + 1, 1, [w, h])
    mask = np.zeros((hi[1] - lo[1], hi[0] - lo[0]), np.uint8)
    cv2.fillConvexPoly(mask, np.round(verts - lo).astype(np.int32), 1)
    if not mask.any():
        return 0.0
    clear = np.ones(mask.shape, np.float32)
    for al in covers:
        clear *= 1.0 - al[lo[1]:hi[1], lo[0]:hi[0]]
    return float(1.0 - clear[mask > 0].mean())


#: a plate counts as in view when wholly inside the frame and at most this share of it is hidden
MAX_HIDDEN = 0.1


def _render_frame(frame, cars, t, size, aspect, overlap):
    """Composite the cars on the road at frame ``t`` onto ``frame`` (in place, far lanes first);
    returns ``[(id, pose, vertices, inside, hidden share)]`` of their plates."""
    w, h = size
    drawn = []
    for car in sorted(cars, key=lambda c: c["lane"]) if overlap else cars:
        placed = _place(car, t, w, h, aspect)
        if placed is None:
            continue
        pose, m, v = placed
        obj = cv2.warpAffine(car["sprite"], m, (w, h), flags=cv2.INTER_LINEAR)
        al = cv2.warpAffine(car["alpha"], m, (w, h), flags=cv2.INTER_LINEAR)
        obj = motion_blur(obj * al[..., None], (0.5 * v, 0.0))
        al = motion_blur(al, (0.5 * v, 0.0))
        frame *= 1.0 - al[..., None]
        frame += obj
        verts = plate_vertices(pose, aspect)[0]
        inside = np.all((verts[:, 0] >= 0) & (verts[:, 0] <= w - 1) & (verts[:, 1] >= 0) & (verts[:, 1] <= h - 1))
        drawn.append((car["id"], pose, verts, bool(inside), al))
    return [(cid, pose, verts, inside, _hidden(verts, [d[4] for d in drawn[k + 1:]], size))
            for k, (cid, pose, verts, inside, _) in enumerate(drawn)]


def _truth_row(t, plate, cols):
    """A ground-truth row: the plate ``(id, pose, vertices, ...)`` in view, or ``None`` for none."""
    if plate is None:
        row = {c: np.nan for c in cols}
        row.update(frame=t, visible=0, id=-1)
        return row
    cid, pose, verts = plate[:3]
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    row = {"frame": t, "visible": 1, "id": cid, "cx": pose[0], "cy": pose[1], "w": hi[0] - lo[0],
           "h": hi[1] - lo[1], "angle_deg": np.rad2deg(pose[2]), "scale": pose[3]}
    for i in range(4):
        row[f"x{i}"], row[f"y{i}"] = verts[i]
    if len(plate) > 3:
        row["hidden"] = plate[3]
    return row


#: ``groundtruth.csv``'s columns (one row per frame); ``objects.csv`` adds ``hidden``
COLUMNS = ["frame", "visible", "id", "cx", "cy", "w", "h", "angle_deg", "scale"] + \
    [f"{c}{i}" for i in range(4) for c in "xy"]
OBJECT_COLUMNS = COLUMNS + ["hidden"]


@atomic_clip
def make_plate_clip(out, *, frames=300, size=(640, 480), seed=0, cars=3, layout="jp", overlap=False, fps=30.0,
                    progress=None):
    """Render a road clip into ``out`` (video.mp4, groundtruth.csv, objects.csv, meta.json); returns
    the meta dict (module docstring)."""
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
    starts, span = _schedule(frames, cars, overlap)
    car_list = [_car(k, t0, span, lay, rng, w, h, k % 3 if overlap else None) for k, t0 in enumerate(starts)]
    phase = rng.uniform(0, 2 * np.pi)
    rows, objects = [], []
    with VideoWriter(out / "video.mp4", fps, (w, h)) as vw:
        for t in range(frames):
            frame = bg * lighting((w, h), t, phase, amplitude=0.2)
            plates = _render_frame(frame, car_list, t, (w, h), lay.aspect, overlap)
            vw.write(add_noise(frame, rng, 4.0))
            seen = [p for p in plates if p[3] and p[4] <= MAX_HIDDEN]
            best = max(seen, key=lambda p: p[1][3], default=None)  # the largest plate in view
            rows.append(_truth_row(t, best, COLUMNS))
            objects += [_truth_row(t, p[:3] + (round(p[4], 4),), OBJECT_COLUMNS)
                        for p in sorted(seen, key=lambda p: p[0])] or [_truth_row(t, None, OBJECT_COLUMNS)]
            if progress:
                progress(1)
    meta = {"kind": "plate", "model": "plate", "frames": frames, "size": [w, h], "fps": fps, "seed": seed,
            "cars": cars, "layout": layout, "aspect": lay.aspect, "overlap": overlap,
            "note": "scale = plate width in px; angle_deg = angle of the non-vertical sides; vertices TL, TR, BR, BL"}
    if overlap:
        meta["max_in_view"] = 3
    write_clip_files(out, rows, COLUMNS, meta)
    write_track_csv(out / "objects.csv", objects, OBJECT_COLUMNS)
    if not any(r["visible"] for r in rows):
        import warnings

        warnings.warn(f"no plate comes wholly into view in the {frames} frame(s): every row of groundtruth.csv and "
                      "objects.csv has visible=0 (empty geometry cells); give more frames",
                      NoPlateWarning, stacklevel=3)
    return meta


def detection_frames(n, *, layout="jp", seed=0, size=(640, 480), widths=(90.0, 180.0), with_plate=True,
                     backgrounds=None):
    """``n`` still road scenes for the plate detector: the scene of :func:`make_plate_clip` (buildings,
    text signs, grilles, lane marks) and, with ``with_plate``, one car whose plate (``layout``) is
    ``widths`` px wide (uniform), sheared by ±6°, parked in the lower half; lighting and sensor noise
    as in the clips (no motion blur: a car the detector has to find first is a car in view).

    ``backgrounds``: BGR frames (e.g. of real clips); each scene's background is one of them (drawn
    at random), resized to ``size``, instead of the synthetic road scene.

    Returns ``(frames, boxes)``: BGR uint8 frames and each plate's bounding box ``(x, y, w, h)``
    (``None`` without a plate)."""
    w, h = int(size[0]), int(size[1])
    lay = LAYOUTS[layout]
    rng = np.random.default_rng(seed)
    frames, boxes = [], []
    for _ in range(n):
        if backgrounds is None:
            img = _background((w, h), rng)
        else:
            img = cv2.resize(backgrounds[int(rng.integers(len(backgrounds)))], (w, h)).astype(np.float32)
        box = None
        if with_plate:
            plate = render_plate(lay, rng, 240)
            sprite, alpha, (px0, py0) = _car_sprite(plate, rng)
            s = rng.uniform(*widths)
            scale = s / plate.shape[1]
            th = np.deg2rad(rng.uniform(-6, 6))
            pcx, pcy = px0 + plate.shape[1] / 2, py0 + plate.shape[0] / 2
            xc, yc = rng.uniform(0.25, 0.75) * w, rng.uniform(0.62, 0.8) * h
            m = np.array([[scale, 0, xc - scale * pcx],
                          [scale * np.tan(th), scale, yc - scale * (pcy + np.tan(th) * pcx)]], np.float32)
            car = cv2.warpAffine(sprite, m, (w, h), flags=cv2.INTER_AREA)
            a = cv2.warpAffine(alpha, m, (w, h), flags=cv2.INTER_LINEAR)[..., None]
            img = img * (1 - a) + car * a
            v = plate_vertices(np.array([[xc, yc, th, s]]), lay.aspect)[0]
            lo, hi = v.min(axis=0), v.max(axis=0)
            box = np.array([lo[0], lo[1], hi[0] - lo[0], hi[1] - lo[1]])
        img = img * lighting((w, h), int(rng.integers(0, 300)), rng.uniform(0, 2 * np.pi), amplitude=0.2)
        frames.append(np.clip(add_noise(img, rng, 4.0), 0, 255).astype(np.uint8))
        boxes.append(box)
    return frames, boxes


class NoPlateWarning(UserWarning):
    """A plate clip in which no plate is ever in view."""
