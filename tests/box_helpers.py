"""Shared by the box model's tests: a textured background and a striped red object moving along a loop,
at known boxes."""

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
