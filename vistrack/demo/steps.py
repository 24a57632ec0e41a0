"""What ``vistrack demo`` shows: a generated clip of an object that jumps in heavy clutter, the box
model's LS-N-IPS, LIS and bootstrap compared on it at about equal time per frame, then the first
frames of a real clip with vistrack's default tracker beside OpenCV's MIL (:func:`compare`: ``eval``'s
pipeline in this process)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from ..data_synth.contour_clip import make_contour_clip
from ..evaluation.experiment import EvalConfig, check_grid_size
from ..evaluation.pipeline import evaluate
from ..io.clips import excerpt_clip
from ..registry import DEFAULT_MODEL, get_model_spec
from ..registry.comparisons import DEMO
from ..reports.eval_report import averages

__all__ = ["DEMO_ENTRIES", "CLIP", "CLIP_FOLDER", "REAL_ENTRIES", "REAL_CLIP", "Excerpt", "find_real_clip",
           "check_demo", "make_demo_clip", "real_excerpt", "compare"]

#: the comparison on the generated clip (:data:`~vistrack.registry.comparisons.DEMO`)
DEMO_ENTRIES = DEMO
#: the generated clip: sudden jumps of 38-51 px (12-16 % of the width, two thirds of the object's size)
#: with probability 0.04 per frame, in heavy clutter
CLIP = {"size": (320, 240), "clutter": "high", "distractor": False, "jump_prob": 0.04, "jump_size": (0.12, 0.16)}
#: where the generated clip goes in the demo's folder
CLIP_FOLDER = Path("clips") / "jumps"
#: the real clip: vistrack's default tracker (the default model's default algorithm) beside OpenCV's MIL
REAL_ENTRIES = ((get_model_spec(DEFAULT_MODEL).default_algo, 100), ("opencv-mil", 1))
REAL_CLIP = Path("shared") / "data" / "real" / "girl_otb"


@dataclass
class Excerpt:
    """The real clip's first frames: the clip, the folder of its excerpt and the frames in it."""

    real: Path
    folder: Path
    frames: int


def find_real_clip():
    """The real clip of step 4 whichever the working folder: ``$VISTRACK_REAL_DATA/girl_otb``, else
    ``shared/data/real/girl_otb`` under the working folder, the installed package's folder or any folder
    above them (a clone's ``../shared``); ``None`` when there is none."""
    env = os.environ.get("VISTRACK_REAL_DATA")
    if env and (Path(env) / REAL_CLIP.name).exists():
        return Path(env) / REAL_CLIP.name
    cwd, pkg = Path.cwd().resolve(), Path(__file__).resolve().parent
    for base in [cwd, *cwd.parents, pkg, *pkg.parents]:
        if (base / REAL_CLIP).exists():
            return base / REAL_CLIP
    return None


def check_demo(frames, runs, real_frames):
    """Before anything is made: the demo's two comparisons (``runs`` runs of :data:`DEMO_ENTRIES` on a clip
    of ``frames`` frames, of :data:`REAL_ENTRIES` on ``real_frames``) checked against memory
    (:func:`~vistrack.evaluation.experiment.check_grid_size`: a one-line ``TooLarge``)."""
    check_grid_size(1, DEMO_ENTRIES, runs, frames)
    check_grid_size(1, REAL_ENTRIES, runs, real_frames)


def make_demo_clip(out, frames, seed):
    """The generated clip (:data:`CLIP`) of ``frames`` frames from seed ``seed + 1`` in ``out/``:data:`CLIP_FOLDER`
    (``out`` made; a one-line ``ValueError`` where it cannot be); returns its folder."""
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"cannot create {out}: {e.strerror}") from None
    # its meta.json names the model the demo tracks it with, which run and eval then take by default
    make_contour_clip(out / CLIP_FOLDER, frames=frames, seed=seed + 1, model=DEFAULT_MODEL, **CLIP)
    return out / CLIP_FOLDER


def real_excerpt(real_clip, folder, frames):
    """The first ``frames`` frames of the real clip ``real_clip`` (``None``: :func:`find_real_clip`;
    ``""``: none) excerpted into ``folder/<its name>`` (:func:`~vistrack.io.clips.excerpt_clip`): an
    :class:`Excerpt`, or ``None`` without a real clip."""
    real = Path(real_clip) if real_clip else (find_real_clip() if real_clip is None else None)
    if real is None or not real.exists():
        return None
    excerpt = Path(folder) / (real.name if real.is_dir() else real.parent.name)
    excerpt_clip(real, excerpt, frames)
    return Excerpt(real, excerpt, sum(1 for _ in (excerpt / "img").iterdir()))


def compare(clip, entries, model, runs, seed, out, **hooks):
    """Evaluate ``entries`` (``(algo, N)`` pairs) with ``model`` on ``clip`` over ``runs`` runs into the folder
    ``out``, as ``vistrack eval`` does (:func:`~vistrack.evaluation.pipeline.evaluate`), on one worker in this
    process (``hooks``: the engine's progress hooks); returns the report's averages table
    (:func:`~vistrack.reports.eval_report.averages`)."""
    cfg = EvalConfig(clips=[clip], algos=[a for a, _ in entries], particles=sorted({n for _, n in entries}),
                     runs=runs, seed=seed, model=model, entries=list(entries))
    evaluate(cfg, out, workers=1, in_process=True, **hooks)
    return averages(out)
