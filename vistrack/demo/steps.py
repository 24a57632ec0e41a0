"""What ``vistrack demo`` shows: a generated clip of an object that jumps in heavy clutter, the box
model's LS-N-IPS, LIS and bootstrap compared on it at about equal time per frame, then the first
frames of a real clip with vistrack's default tracker beside OpenCV's MIL (:func:`compare`: ``eval``'s
pipeline in this process); :func:`run_demo` is the whole of it."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from .. import kernels
from ..data_synth.contour_clip import make_contour_clip
from ..evaluation.experiment import EvalConfig, check_grid_size
from ..evaluation.pipeline import evaluate
from ..io.clips import excerpt_clip
from ..registry import DEFAULT_MODEL, DEFAULT_PARTICLES, algos_for, get_model_spec
from ..registry.comparisons import DEMO, DEMO_REAL
from ..reports.eval_report import averages
from ..session.plan import track_video
from ..system.compiling import compiling

__all__ = ["DemoConfig", "DEMO_ENTRIES", "CLIP", "CLIP_FOLDER", "REAL_ENTRIES", "REAL_CLIP", "Excerpt",
           "find_real_clip", "check_demo", "make_demo_clip", "real_excerpt", "compare", "run_demo", "runs_phrase"]

#: the comparison on the generated clip (:data:`~vistrack.registry.comparisons.DEMO`)
DEMO_ENTRIES = DEMO
#: the generated clip: sudden jumps of 38-51 px (12-16 % of the width, two thirds of the object's size)
#: with probability 0.04 per frame, in heavy clutter
CLIP = {"size": (320, 240), "clutter": "high", "distractor": False, "jump_prob": 0.04, "jump_size": (0.12, 0.16)}
#: where the generated clip goes in the demo's folder
CLIP_FOLDER = Path("clips") / "jumps"
#: the real clip: vistrack's default tracker (the default model's default algorithm at the default N) beside
#: OpenCV's MIL (:data:`~vistrack.registry.comparisons.DEMO_REAL`)
REAL_ENTRIES = ((get_model_spec(DEFAULT_MODEL).default_algo, DEFAULT_PARTICLES), *DEMO_REAL)
REAL_CLIP = Path("shared") / "data" / "real" / "girl_otb"


@dataclass(frozen=True)
class DemoConfig:
    """``vistrack demo``'s options with their defaults: the folder it writes into, the generated clip's frames,
    the runs of each comparison, the root seed and the frames of the real clip (``real_clip``: ``None``, found
    by :func:`find_real_clip`; ``""``: none)."""

    out: str = "vistrack-demo"
    frames: int = 100
    runs: int = 4
    seed: int = 0
    real_clip: str | None = None
    real_frames: int = 60


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


def runs_phrase(n):
    """``1 run``, ``4 runs``."""
    return f"{n} run{'' if n == 1 else 's'}"


def _entries(entries):
    """``ls-n-ips N=30, lis N=30, ...``."""
    return ", ".join(f"{a} N={n}" for a, n in entries)


def _step4(real, real_clip, real_frames, runs):
    """Step 4's line: the real clip's excerpt, or where none was found."""
    if real is None:
        where = real_clip or ("(none given)" if real_clip == "" else f"{REAL_CLIP} above {Path.cwd()} or the package")
        return (f"4/4 skipped: no real clip at {where} (--real-clip DIR: a clip with box ground truth, e.g. "
                "OTB's Girl; or set VISTRACK_REAL_DATA to the folder holding girl_otb)")
    took = f"the first {real_frames} frames" if real.frames >= real_frames else \
        f"all {real.frames} frames (fewer than --real-frames {real_frames})"
    return (f"4/4 {took} of {real.real} ({real.folder}): vistrack's default box tracker "
            f"({REAL_ENTRIES[0][0].upper()} N={REAL_ENTRIES[0][1]}) beside OpenCV MIL, {runs_phrase(runs)} each")


def run_demo(out=DemoConfig.out, *, frames=DemoConfig.frames, runs=DemoConfig.runs, seed=DemoConfig.seed,
             real_clip=DemoConfig.real_clip, real_frames=DemoConfig.real_frames, say=print, tracking=None, grid=None):
    """``vistrack demo`` into the folder ``out`` (the defaults are :class:`DemoConfig`'s): the generated clip of
    ``frames`` frames (:func:`make_demo_clip`) tracked once per algorithm of :data:`DEMO_ENTRIES` into an
    annotated video and a track CSV each (:func:`~vistrack.session.plan.track_video`, the kernels of every step
    compiled first), compared over ``runs`` runs (:func:`compare`), then the first ``real_frames`` frames of
    the real clip (:func:`real_excerpt`) compared with :data:`REAL_ENTRIES` (skipped, saying so, without one).
    Returns the files made.

    ``say(text)`` hears each step's line, each run's summary and the tables; ``tracking`` holds the hooks
    of :func:`~vistrack.session.plan.track_video` (``note``, ``lost``, ``compiling_progress``, ``frames``) and
    ``grid`` those of the engine (``progress``, ``on_ready``, ``notify``)."""
    out, made, (w, h), tracking, grid = Path(out), [], CLIP["size"], dict(tracking or {}), grid or {}
    check_demo(frames, runs, real_frames)
    say(f"1/4 generating a {frames}-frame {w}x{h} clip in {out / CLIP_FOLDER}: a textured object in heavy clutter "
        "that jumps 38-51 px every 25 frames or so")
    clip = make_demo_clip(out, frames, seed)
    say("2/4 tracking it once per algorithm (annotated video + track CSV)")
    with compiling(tracking.pop("compiling_progress", None), kernels.use()) as compiler:  # one count for the demo
        ours = [a for a, _ in (*DEMO_ENTRIES, *REAL_ENTRIES) if a in algos_for(DEFAULT_MODEL)]
        compiler.compile(DEFAULT_MODEL, list(dict.fromkeys(ours)))
        for algo, n in DEMO_ENTRIES:
            made += [out / f"jumps-{algo}.mp4", out / f"jumps-{algo}.csv"]
            say(f"  {algo} N={n}:")
            _, _, report = track_video(clip, model=DEFAULT_MODEL, algo=algo, particles=n, seed=seed, init_gt="",
                                       outputs={"out_path": made[-2], "track_path": made[-1]}, **tracking)
            say("\n".join(report.notes + report.lines))
        say(f"3/4 comparing them over {runs_phrase(runs)} (as vistrack eval does): " + _entries(DEMO_ENTRIES))
        say(compare(clip, DEMO_ENTRIES, DEFAULT_MODEL, runs, seed, out / "eval", **grid))
        real = real_excerpt(real_clip, out / "clips", real_frames)
        say(_step4(real, real_clip, real_frames, runs))
        if real is not None:
            say(compare(real.folder, REAL_ENTRIES, DEFAULT_MODEL, runs, seed, out / "eval-real", **grid))
    evals = ("eval", "eval-real")[:1 + (real is not None)]
    return made + [out / e / f"report.{x}" for e in evals for x in ("md", "html")]
