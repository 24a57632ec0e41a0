"""Landmark shape sequences (seed 000, §3–4): simulated states and observations, and video clips."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vistrack.io.video import VideoWriter
from vistrack.models.landmarks.model import VIDEO_DYNAMICS, Landmarks, simulate
from vistrack.models.landmarks.model import sample_observations as observe

from .scene import add_noise, atomic_clip, clutter_background, lighting, smooth_noise, write_clip_files

__all__ = ["simulate", "observe", "make_landmark_clip", "draw_blob"]


def draw_blob(img, x, y, sigma, amplitude):
    """Add a Gaussian blob of std ``sigma`` px centred at the sub-pixel ``(x, y)`` to ``img`` in place."""
    h, w = img.shape[:2]
    r = int(np.ceil(4 * sigma))
    x0, x1 = max(int(x) - r, 0), min(int(x) + r + 2, w)
    y0, y1 = max(int(y) - r, 0), min(int(y) + r + 2, h)
    if x0 >= x1 or y0 >= y1:
        return
    gx = np.exp(-0.5 * ((np.arange(x0, x1) - x) / sigma) ** 2)
    gy = np.exp(-0.5 * ((np.arange(y0, y1) - y) / sigma) ** 2)
    patch = (amplitude * np.outer(gy, gx)).astype(np.float32)
    img[y0:y1, x0:x1] += patch[:, :, None] if img.ndim == 3 else patch


def _checked(frames, k, size):
    """The frame size ``(w, h)`` of a landmark clip, after checking the clip's arguments."""
    if frames < 1:
        raise ValueError(f"need at least one frame, got {frames}")
    if k < 3:
        raise ValueError(f"need at least 3 landmarks, got {k}")
    w, h = int(size[0]), int(size[1])
    if w < 128 or h < 96:
        raise ValueError(f"frame size {w}x{h} is too small for landmark clips (need at least 128x96)")
    return w, h


def _truth_row(t, centre, x, pts, occ):
    """One ``groundtruth.csv`` row: the landmarks' bounding box, the state's angle and scale, every
    landmark's position and whether it was hidden."""
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    row = {"frame": t, "visible": 1, "cx": centre[0], "cy": centre[1], "w": hi[0] - lo[0],
           "h": hi[1] - lo[1], "angle_deg": float(np.rad2deg(x[0, 1])), "scale": float(np.exp(x[0, 0]))}
    row.update({f"lx{i}": pts[i, 0] for i in range(len(pts))})
    row.update({f"ly{i}": pts[i, 1] for i in range(len(pts))})
    row.update({f"occ{i}": int(occ[i]) for i in range(len(pts))})
    return row


def _landmark_meta(frames, w, h, fps, seed, k, centre, scale_px, model, rows, sigma_blob, n_cl, occlusion):
    """``meta.json`` of a landmark clip (the template: the landmarks of frame 0)."""
    first = [[rows[0][f"lx{i}"], rows[0][f"ly{i}"]] for i in range(k)]
    return {
        "kind": "landmarks",
        "model": "landmarks",
        "frames": frames,
        "size": [w, h],
        "fps": fps,
        "seed": seed,
        "k": k,
        "centre": centre.tolist(),
        "scale_px": float(scale_px),
        "theta0": model.theta0,
        "template": {"landmarks": np.round(first, 4).tolist(),
                     "note": "landmark positions (px) in frame 0; configuration h = (p - centre) / scale_px"},
        "dynamics": {k_: (v if np.isscalar(v) else list(v)) for k_, v in VIDEO_DYNAMICS.items()},
        "blob_sigma_px": sigma_blob,
        "clutter_blobs": n_cl,
        "occlusion_rate": occlusion,
        "noise_std": 4.0,
    }


@atomic_clip
def make_landmark_clip(out, *, k=5, frames=200, size=(640, 480), seed=0, clutter_blobs=6, occlusion=0.01,
                       fps=30.0, progress=None):
    """Render a landmark clip into ``out`` (video.mp4, groundtruth.csv, meta.json).

    ``K`` bright blobs at ``centre + scale_px · h_t`` (``h_t = z_t e^{s_t + jθ_t}``
    follows the model (5) with :data:`~vistrack.models.landmarks.model.VIDEO_DYNAMICS`,
    from the regular K-gon), so scale and rotation are about the image centre
    and the shape deforms. Clutter: ``clutter_blobs`` identical blobs drifting
    over a textured background with edges; each landmark is occluded (not
    drawn) for 3–10 frames with probability ``occlusion`` per frame. Lighting
    change and sensor noise. Ground truth: every landmark's position per frame
    (``lx0.., ly0..``) and whether it was drawn (``occ0..`` = 1 when occluded).
    """
    w, h = _checked(frames, k, size)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    scale_px = 0.3 * min(w, h) * np.sqrt(k)  # landmarks 0.3·min(w, h) from the centre
    centre = np.array([w / 2, h / 2])
    model = Landmarks(k, z0=None, theta0=float(rng.uniform(-0.5, 0.5)), **VIDEO_DYNAMICS)
    bg = 0.55 * clutter_background((w, h), rng, int(40 * w * h / (640 * 480)))
    bg += 30 * np.stack([smooth_noise((h, w), rng, 6)] * 3, axis=-1)
    sigma_blob = max(1.5, 0.005 * min(w, h))
    amp = 150.0
    n_cl = int(clutter_blobs)
    cl_pos = np.column_stack([rng.uniform(0.1, 0.9, n_cl) * w, rng.uniform(0.1, 0.9, n_cl) * h])
    cl_vel = rng.normal(0, 1.0, (n_cl, 2))
    occluded_until = np.full(k, -1)
    phase = rng.uniform(0, 2 * np.pi)
    x = model.prior_mean[None].copy()
    cols = ["frame", "visible", "cx", "cy", "w", "h", "angle_deg", "scale"]
    cols += [f"lx{i}" for i in range(k)] + [f"ly{i}" for i in range(k)] + [f"occ{i}" for i in range(k)]
    rows = []
    with VideoWriter(out / "video.mp4", fps, (w, h)) as vw:
        for t in range(frames):
            if t > 0:
                x = model.predict(x, rng)
            pts = centre + scale_px * np.column_stack([model.configuration(x)[0].real, model.configuration(x)[0].imag])
            start = (rng.random(k) < occlusion) & (occluded_until < t)
            occluded_until[start] = t + rng.integers(3, 11, start.sum())
            occ = occluded_until >= t
            frame = bg * lighting((w, h), t, phase, amplitude=0.15)
            for i in range(k):
                if not occ[i]:
                    draw_blob(frame, pts[i, 0], pts[i, 1], sigma_blob, amp)
            cl_vel = 0.95 * cl_vel + rng.normal(0, 0.3, cl_vel.shape)
            cl_pos = np.clip(cl_pos + cl_vel, [5, 5], [w - 5, h - 5])
            for cx_, cy_ in cl_pos:
                draw_blob(frame, cx_, cy_, sigma_blob, amp)
            vw.write(add_noise(frame, rng, 4.0))
            rows.append(_truth_row(t, centre, x, pts, occ))
            if progress:
                progress(1)
    meta = _landmark_meta(frames, w, h, fps, seed, k, centre, scale_px, model, rows, sigma_blob, n_cl, occlusion)
    write_clip_files(out, rows, cols, meta)
    return meta
