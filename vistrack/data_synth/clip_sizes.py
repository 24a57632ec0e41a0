"""The sizes a synthetic clip or suite is given, checked before anything is rendered: against the disk
(frames of a size), memory (the cars' sprites, the landmark model) and sense (the landmarks and clutter
blobs a frame can show apart). Every check is one line (:class:`~vistrack.system.resources.TooLarge`,
through :func:`~vistrack.system.resources.check_disk` and :func:`~vistrack.system.resources.check_memory`)
naming the size and what fits; :func:`~vistrack.data_synth.scene.atomic_clip` runs them for every clip
maker."""

from __future__ import annotations

import math

from ..system.resources import TooLarge, check_disk, check_memory

__all__ = ["CLIP_BYTES", "CLIP_FRAME_BYTES", "CLIP_PIXEL_BYTES", "CAR_BYTES", "LANDMARK_BYTES", "check_suite_disk",
           "check_clip_sizes"]

#: the least a synthetic clip takes on disk: its small files, and per frame its ground-truth rows and
#: bytes per pixel of video (a 640x480 plate clip takes 0.04, a 320x240 contour clip 0.03)
CLIP_BYTES, CLIP_FRAME_BYTES, CLIP_PIXEL_BYTES = 1024, 100, 0.01
#: memory of one car of a plate clip: its sprite and alpha (float32, about 1008x504 px) and its plate
CAR_BYTES = 8_500_000
#: memory of the landmark model per K² (its state has about 2 K² components, several arrays of it: 84-104
#: bytes per K² measured for K = 25-200), with room for the per-frame copies
LANDMARK_BYTES = 400


def check_suite_disk(out, clips, frames, size):
    """Raise :class:`~vistrack.system.resources.TooLarge` (one line, before any clip is made) when
    ``clips`` clips of ``frames`` frames of ``size`` would not fit on the disk holding ``out``
    (:data:`CLIP_BYTES`, :data:`CLIP_FRAME_BYTES`, :data:`CLIP_PIXEL_BYTES`: the least they take); the
    advice is fewer clips, or fewer frames where not even one fits."""
    per_frame = CLIP_FRAME_BYTES + CLIP_PIXEL_BYTES * size[0] * size[1]
    each = CLIP_BYTES + int(frames) * per_frame

    def most(free):
        if free >= each:
            return f"give at most {int(free // each)} clips"
        return f"not even one clip fits: give at most {max(0, int((free - CLIP_BYTES) // per_frame))} --frames"

    what = f"{clips} clips of {frames} frames at {size[0]}x{size[1]} need" if clips != 1 else \
        f"a clip of {frames} frames at {size[0]}x{size[1]} needs"
    check_disk(int(clips) * each, out, what, most)


def _check_apart(count, most, things, size, where, option):
    """``count`` ``things`` no more than the ``most`` a frame of ``size`` shows apart (``where``): else one line."""
    if count > most:
        raise TooLarge(f"{option} {count}: a {size[0]}x{size[1]} frame shows at most {most} {things} apart{where}; "
                       f"give at most {most}")


def check_clip_sizes(out, frames=None, size=None, *, cars=None, k=None, clutter_blobs=None):
    """Raise :class:`~vistrack.system.resources.TooLarge` (one line) before a clip is rendered into ``out``
    when its ``frames`` of ``size`` would not fit on the disk (:func:`check_suite_disk`), its ``cars``'
    sprites in memory (:data:`CAR_BYTES` each), its ``k`` landmarks' model in memory
    (:data:`LANDMARK_BYTES` per K²), or when a ``size`` frame cannot show ``k`` landmarks on their ring or
    ``clutter_blobs`` blobs apart (a blob's σ is 0.5 % of the shorter side, at least 1.5 px: the ring of
    radius 0.3 of the shorter side holds one landmark per 4 σ, a frame one blob per (3 σ)²)."""
    if frames is not None and size is not None:
        check_suite_disk(out, 1, frames, size)
    if cars is not None:
        check_memory(int(cars) * CAR_BYTES, f"--cars {cars}: their sprites need",
                     lambda room: f"give at most {int(room // CAR_BYTES)} cars")
    if size is None:
        return
    sigma = max(1.5, 0.005 * min(size))
    if k is not None:
        _check_apart(int(k), int(2 * math.pi * 0.3 * min(size) / (4 * sigma)), "landmarks", size, " on their ring",
                     "--k")
        check_memory(LANDMARK_BYTES * int(k) ** 2, f"--k {k}: the landmark model needs",
                     lambda room: f"give at most {int(math.sqrt(room / LANDMARK_BYTES))} landmarks")
    if clutter_blobs is not None:
        _check_apart(int(clutter_blobs), int(size[0] * size[1] / (3 * sigma) ** 2), "blobs", size, "",
                     "--clutter-blobs")

