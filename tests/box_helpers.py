"""Shared by the box model's tests: a textured background and a striped red object moving along a loop,
at known boxes; a patterned box moving right and down; an orange square that leaves and comes back elsewhere."""

import cv2
import numpy as np

H, W = 240, 320
OBJ = (44, 32)  # object width, height


def background(rng, grey=False):
    """A smooth green-grey texture: structure everywhere, none of the object's colour."""
    noise = cv2.GaussianBlur(rng.normal(0, 1, (H, W)).astype(np.float32), (0, 0), 4)
    base = 110 + 400 * noise
    img = np.dstack([base * 0.8, base, base * 0.85]).clip(0, 255).astype(np.uint8)
    return cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if grey else img


def draw_object(img, cx, cy):
    """A red-orange rectangle with dark stripes (colour and layout), centred at (cx, cy)."""
    out = img.copy()
    w, h = OBJ
    x0, y0 = int(round(cx - w / 2)), int(round(cy - h / 2))
    colour = (30, 60, 220) if out.ndim == 3 else 200
    cv2.rectangle(out, (x0, y0), (x0 + w - 1, y0 + h - 1), colour, -1)
    for k in range(3):
        cv2.rectangle(out, (x0 + 6 + 13 * k, y0 + 6), (x0 + 10 + 13 * k, y0 + h - 7),
                      (20, 20, 90) if out.ndim == 3 else 40, -1)
    return out


def obj_box(cx, cy):
    return (cx - OBJ[0] / 2, cy - OBJ[1] / 2, OBJ[0], OBJ[1])


def path(t):
    """The object's centre at frame t: a loop through the frame."""
    return 160 + 80 * np.sin(0.05 * t), 120 + 50 * np.sin(0.08 * t + 0.5)


def clip_frames(n, grey=False, seed=0):
    bg = background(np.random.default_rng(seed), grey)
    return [draw_object(bg, *np.round(path(t))) for t in range(n)]

def moving_box_frames(n=20, seed=0):
    """A textured background with a coloured, patterned box moving right and down."""
    rng = np.random.default_rng(seed)
    bg = cv2.GaussianBlur(rng.integers(0, 256, (120, 160, 3), dtype=np.uint8), (0, 0), 2)
    frames = []
    for t in range(n):
        f = bg.copy()
        x, y = 40 + 2 * t, 30 + t
        cv2.rectangle(f, (x, y), (x + 30, y + 36), (30, 200, 220), -1)
        cv2.circle(f, (x + 15, y + 18), 8, (200, 40, 40), -1)
        frames.append(f)
    return frames, (40.0, 30.0, 31.0, 37.0)


GONE, BACK = 15, 35  # the object gone from GONE, back (elsewhere) from BACK


def reappearing_clip(n=48):
    """An orange striped square moving right 4 px per frame over a textured background, gone for 20 frames,
    back 90 px lower and moving left; and its boxes."""
    rng = np.random.default_rng(4)
    bg = cv2.GaussianBlur(rng.integers(70, 180, (200, 260, 3)).astype(np.uint8), (0, 0), 3)
    obj = np.zeros((26, 26, 3), np.uint8)
    obj[:] = (30, 120, 230)  # orange, with dark stripes
    obj[::6] = 20
    frames, boxes = [], []
    for t in range(n):
        f = bg.copy()
        x, y = (30 + 4 * t, 40) if t < BACK else (150 - 2 * (t - BACK), 130)
        if not GONE <= t < BACK:
            f[y:y + 26, x:x + 26] = obj
        frames.append(f)
        boxes.append((x, y, 26, 26))
    return frames, boxes
