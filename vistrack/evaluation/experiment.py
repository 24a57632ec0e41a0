"""Batch evaluation: clip × algorithm × N × run -> tasks -> results (docs/architecture.md, evaluation protocol).

Every task tracks one clip once and writes its own result file
``tasks/<clip>__<algo>__N<n>__r<run>.json`` (written to a temporary name and
renamed, so a file that exists is complete). Finished tasks are skipped on
``resume``; a worker that dies loses only its own task. Run ``r`` draws from
:func:`~vistrack.core.seeds.run_seed` ``(seed, r)`` on every clip (the same stream
for every algorithm and N: common random numbers), the stream of ``vistrack run
--seed S --run r``, so results do not depend on the number of workers or the order
in which tasks run. The reproductions (:func:`entry_tasks`) keep the streams their
published tables were computed with: run ``r`` on clip ``c`` draws from
``SeedSequence(seed).spawn(clips)[c].spawn(runs)[r]``.

Boxes are ``(cx ± w/2, cy ± h/2)`` with ``cx, cy`` the pose centre, as in
groundtruth.csv. Per frame a task records the centre error, whether the tracker is lost
(centre error > 50 px at 240-px width, scaled — thesis §3.2.5), the IoU of the
estimated box with the true box, ESS and ms, whether the tracker reported the object
(``reported``: vistrack's ``visible``, OpenCV's ``update`` result, a result file's non-empty
box) and its confidence (``confidence``; ``None`` for a tracker without one). :func:`summarize`
turns the task files into per clip × algo × N summaries (mean error over frames not lost,
P(lost) per frame and overall, the share of frames reported lost, success AUC over IoU
thresholds 0..1 and with the frames reported lost as empty, VOT-LT's long-term precision,
recall and F-score, precision at 20 px, frames/s, mean ESS).
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..batch.tasks import load_task_results, save_result
from ..core.seeds import run_seed
from ..io.clips import GroundTruthWarning, load_clip, sequence_name
from ..io.remote import is_url, url_version
from ..io.results_format import find_result_file, read_result_file
from ..io.video import VideoError
from ..loop.stepper import Stepper
from ..registry import (
    ALGORITHMS,
    BASELINES,
    DEFAULT_MODEL,
    build_model,
    check_algo,
    check_baseline,
    default_comparison,
    get_model_spec,
    is_baseline,
    make_filter,
    runs_once,
)
from ..registry.builders import start_frame
from ..scoring.aggregate import summarize as metrics_summarize
from ..scoring.metrics import score_frames
from ..system.resources import check_memory, prepare_worker
from .multi_target import run_plates_task, score_plates_tasks

__all__ = ["EvalConfig", "task_list", "check_task_grid", "check_grid_size", "entry_tasks", "entries_config",
           "run_task", "summarize", "check_algos", "score_boxes",
           "score_result_file", "result_files", "ResultsLengthWarning", "dask_setup"]


@dataclass
class EvalConfig:
    """One evaluation: clips × (algorithm, N) × runs (:func:`task_list` turns it into tasks).

    Attributes
    ----------
    clips : list
        Clip folders, videos or image folders with ground truth.
    algos : list of str
        Particle filters or comparison trackers (:data:`~vistrack.registry.baseline_specs.BASELINES`).
    particles : list of int
        Numbers of particles ``N``; every algorithm runs at every ``N``.
    runs : int
        Runs per clip, algorithm and ``N``.
    seed : int
        Root seed: run ``r`` draws from :func:`~vistrack.core.seeds.run_seed` ``(seed, r)`` on every clip
        (``vistrack run --seed seed --run r``'s stream).
    model : str
        A registered model (:mod:`vistrack.registry`).
    entries : list of (str, int) or None
        Explicit ``(algo, N)`` pairs instead of the ``algos × particles`` grid.
    targets : int or None
        Several targets at once: the plate model's ``targets`` slots, scored against each clip's
        ``objects.csv`` (:mod:`vistrack.evaluation.multi_target`).

    An :class:`~vistrack.batch.cluster.Experiment`: :meth:`tasks`, :attr:`runner`, :meth:`results`.
    """

    clips: list
    algos: list = field(default_factory=lambda: list(default_comparison()))
    particles: list = field(default_factory=lambda: [100, 750])
    runs: int = 20
    seed: int = 0
    model: str = DEFAULT_MODEL
    #: explicit (algo, N) pairs instead of the algos × particles grid
    entries: list | None = None
    targets: int | None = None

    def pairs(self):
        """The ``(algo, N)`` pairs: :attr:`entries`, else every algorithm at every N (a comparison
        tracker at N 1)."""
        return self.entries or [(a, n) for a in self.algos for n in ([1] if is_baseline(a) else self.particles)]

    def tasks(self):
        """:func:`task_list` of the clips, each with ``targets`` when tracking several."""
        tasks = task_list(self, self.clips)
        if self.targets is not None:
            for t in tasks:
                t["targets"] = self.targets
        return tasks

    @property
    def runner(self):
        """:func:`run_task`, or with ``targets`` :func:`~vistrack.evaluation.multi_target.run_plates_task`."""
        return run_task if self.targets is None else run_plates_task

    def results(self, tasks, out_dir):
        """The task results (:func:`~vistrack.batch.tasks.load_task_results`); with ``targets`` their
        scores (:func:`~vistrack.evaluation.multi_target.score_plates_tasks`)."""
        return load_task_results(tasks, out_dir) if self.targets is None else score_plates_tasks(tasks, out_dir)


def check_algos(algos, model=None, targets=False):
    """Raise ``ValueError`` (one line) for an unknown algorithm, a comparison tracker this installation
    cannot run (its :attr:`~vistrack.registry.baseline_specs.BaselineSpec.check`), or (given ``model``) an
    algorithm that does not run on that model (with ``targets``: on its several-target form; the line names
    those that do, :func:`vistrack.registry.check_algo`)."""
    for a in algos:
        if is_baseline(a):
            check_baseline(a)
        elif a not in ALGORITHMS:
            known = sorted(set(ALGORITHMS) | set(BASELINES))
            raise ValueError(f"unknown algorithm {a!r}; choose from {', '.join(known)}")
        elif model is not None:
            check_algo(model, a, targets, who=f"--algos {a}")


def _name(clip):
    return sequence_name(clip).replace("__", "_")


#: memory a grid's task takes in this process: its dict and seed stream, Dask's future and
#: scheduler state (about 6 KB measured with an in-process cluster), and its result when the
#: summaries are made, per frame of its clip (the per-frame lists read back from JSON)
TASK_BYTES, TASK_FRAME_BYTES = 20_000, 500


def check_task_grid(clips, pairs, runs, available=None):
    """Raise :class:`~vistrack.system.resources.TooLarge` (one line, before any task is made) when the
    grid of ``clips`` x ``pairs`` (algorithm, N) x ``runs`` would not fit in memory
    (:func:`check_grid_size`, with the frames of the longest local clip). Returns the number of tasks."""
    return check_grid_size(len(clips), pairs, runs, _longest(clips), available)


def check_grid_size(clips, pairs, runs, frames=300, available=None):
    """Raise :class:`~vistrack.system.resources.TooLarge` when a grid of ``clips`` clips (of ``frames``
    frames) x ``pairs`` (algorithm, N) x ``runs`` would not fit in memory: its tasks and their
    results (:data:`TASK_BYTES`, :data:`TASK_FRAME_BYTES`). A deterministic comparison tracker runs once
    (:func:`~vistrack.registry.baseline_specs.runs_once`). Returns the number of tasks."""
    pairs = list(pairs)
    fixed = sum(runs_once(a) for a, _ in pairs)
    n = clips * ((len(pairs) - fixed) * int(runs) + fixed)
    each = TASK_BYTES + TASK_FRAME_BYTES * int(frames)

    def most(room):
        runs_fit = (room // each // max(clips, 1) - fixed) // max(len(pairs) - fixed, 1)
        return f"give at most {int(runs_fit)} runs" if runs_fit >= 1 else "give fewer clips or algorithms"

    check_memory(n * each, f"a grid of {n} tasks ({clips} clip(s) x {len(pairs)} algorithm and N pair(s) x "
                 f"{runs} run(s)) needs", most, available=available)
    return n


def _longest(clips, default=300):
    """The most frames of the local ``clips`` (``default`` for URLs and where it is not known)."""
    most = default
    for c in clips:
        if not is_url(c):
            try:
                most = max(most, load_clip(c).source.frame_count or 0)
            except (OSError, ValueError):
                pass
    return most


def task_list(cfg, clips):
    """All tasks as dicts ``{clip, clip_index, algo, particles, run, seed_seq, model, name}``, the grid
    checked against memory first (:func:`check_task_grid`): run ``r`` draws from
    :func:`~vistrack.core.seeds.run_seed` ``(cfg.seed, r)``; a deterministic comparison tracker runs once
    (:func:`~vistrack.registry.baseline_specs.runs_once`; a randomised one as many times as the filters)."""
    pairs = cfg.pairs()
    check_task_grid(clips, pairs, cfg.runs)
    tasks = []
    for ci, clip in enumerate(clips):
        # a clip given as a URL: the server's version of it now (its validators), which every task's
        # copy must match and which its fingerprint records (--resume after a change runs it again)
        version = {"clip_version": url_version(clip)} if is_url(clip) else {}
        for algo, n in pairs:
            for r in range(cfg.runs):
                if runs_once(algo) and r > 0:
                    continue  # deterministic: one run
                tasks.append({"clip": str(clip), "clip_index": ci, "algo": algo, "particles": int(n), "run": r,
                              "seed_seq": run_seed(cfg.seed, r), "model": cfg.model,
                              "name": f"{ci:03d}_{_name(clip)}__{algo}__N{n}__r{r}", **version})
    return tasks


def entry_tasks(cfg, model):
    """The tasks of an experiment config with ``clips``, ``entries`` (algo, N), ``runs`` and
    ``seed`` (the contour and plate reproductions) on ``model``; lost by the thesis's rules
    (the contour's 50 px at 240-px width, the plate's vertex rule)."""
    ev = EvalConfig(clips=list(cfg.clips), entries=[tuple(e) for e in cfg.entries], runs=cfg.runs, seed=cfg.seed,
                    model=model)
    tasks = task_list(ev, list(cfg.clips))
    for t in tasks:
        t["lost_rule"] = "thesis"
        # the published tables' streams: SeedSequence(seed).spawn(clips)[c].spawn(runs)[r]
        t["seed_seq"] = np.random.SeedSequence(cfg.seed, spawn_key=(t["clip_index"], t["run"]))
    return tasks


def entries_config(cfg):
    """Such a config as a JSON-ready dict."""
    d = asdict(cfg)
    d["clips"] = [str(c) for c in cfg.clips]
    d["entries"] = [list(e) for e in cfg.entries]
    return d


def _by_index(values, index):
    """Rows placed at their frame ``index``: frames that failed to decode (absent indices) are
    NaN, so they count as lost rather than shifting every later frame against the truth."""
    values, index = np.asarray(values, float), np.asarray(index, int)
    if np.array_equal(index, np.arange(len(index))):
        return values
    out = np.full((index.max() + 1,) + values.shape[1:], np.nan)
    out[index] = values
    return out


def _truth_boxes(t):
    return np.stack([t["cx"] - t["w"] / 2, t["cy"] - t["h"] / 2, t["w"], t["h"]], axis=1)


def dask_setup(worker):
    """Dask preload hook of the LocalCluster's worker processes (``preload=["vistrack.evaluation.experiment"]``).

    Ctrl-C reaches the whole process group; it is the client's to handle (it closes the cluster,
    which ends the workers), so a worker ignores SIGINT rather than print a traceback, and keeps
    distributed's warnings (tasks cancelled at shutdown) to itself.
    """
    import logging
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    logging.getLogger("distributed").setLevel(logging.ERROR)


def run_task(task, out_dir):
    """Engine runner: track one clip once; write its result under ``out_dir``
    (:func:`~vistrack.batch.tasks.save_result`); return its path."""
    prepare_worker()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GroundTruthWarning)  # said once, when eval found the clips
        clip = load_clip(task["clip"])
    source = _remote_source(clip, task)
    # the run starts at the first frame with a ground-truth box (earlier frames: no estimate, not scored)
    start = start_frame(clip, None, "")
    frames = [(i, f) for i, f in clip.source if i >= start]
    algo, n = task["algo"], task["particles"]
    # eval: the object's own size (the plate's vertex rule for plates); reproduce: the thesis's
    rule = "centre" if task.get("lost_rule") == "thesis" else "size"
    reported, vertices, aspect = [], [], None
    shown, conf = None, None  # what the tracker reported per frame, its confidence
    if is_baseline(algo):
        boxes, ms, index = BASELINES[algo].track(clip.first_box(), frames)
        boxes, ess = _by_index(boxes, index), np.full(index.max() + 1, np.nan)
    else:
        spec = get_model_spec(task["model"])
        model = build_model(task["model"], clip, init_gt="", **task.get("model_params", {}))
        filt = make_filter(algo, model)
        rng = np.random.default_rng(task["seed_seq"])
        est, ms, ess, index, shown, conf = [], [], [], [], [], []
        for res in Stepper(filt, n, rng).steps(frames):
            index.append(res.index)
            est.append(res.estimate)
            ms.append(res.ms)
            ess.append(res.ess)
            shown.append(res.visible)
            conf.append(np.nan if res.confidence is None else res.confidence)
            if spec.lost_rule == "plate":  # the plate rule scores what was reported
                reported.append(res.visible)
                vertices.append(model.vertices(res.estimate)[0])
        est = np.array(est)
        wh = model.box(est)[:, 2:]
        # boxes centred on the pose centre, as groundtruth.csv's (cx, cy, w, h)
        boxes = _by_index(np.concatenate([est[:, :2] - wh / 2, wh], axis=1), index)
        ms, ess = np.array(ms), _by_index(np.array(ess), index)
        shown = np.nan_to_num(_by_index(np.array(shown, float), index)) > 0  # a frame not decoded: not reported
        conf = _by_index(np.array(conf, float), index) if np.isfinite(conf).any() else None
        if spec.lost_rule == "plate":  # placed at their frames too: not reported before the start or where undecoded
            rule, aspect = "plate", model.layout.aspect
            reported = np.nan_to_num(_by_index(np.array(reported, float), index)).astype(bool).tolist()
            vertices = _by_index(np.array(vertices, float), index)
    result = score_boxes(clip, boxes, rule=rule, reported=reported, vertices=vertices, aspect=aspect, shown=shown,
                         confidence=conf)
    result.update({"clip": task["clip"], "algo": algo, "particles": n, "run": task["run"],
                   "ms": [float(v) for v in ms[:result["frames"]]],
                   "ess": [None if not np.isfinite(v) else float(v) for v in ess[:result["frames"]]], **source})
    return save_result(out_dir, task, result)


def _remote_source(clip, task):
    """``{"source": ...}`` for a task result on a clip given as a URL (:meth:`Remote.record`: the
    server's version and whether a cached copy was used), ``{}`` for a local clip; a
    :class:`VideoError` when the copy is not the version the evaluation started with (the clip
    changed on the server while it ran)."""
    remote = clip.remote
    if remote is None:
        return {}
    want = task.get("clip_version")
    if want is not None and remote.version != want:
        raise VideoError(f"{task['clip']} changed on the server while the evaluation ran (its ETag, Last-Modified "
                         "or length differ from those it had at the start): run the evaluation again")
    return {"source": remote.record()}


def score_boxes(clip, boxes, *, rule="size", reported=(), vertices=(), aspect=None, shown=None, confidence=None):
    """Per-frame measures of ``boxes (frames, 4)`` (``x, y, w, h``; NaN where there is no
    estimate) against ``clip``'s ground truth (:func:`~vistrack.scoring.metrics.score_frames`:
    ``frames``, ``visible``, ``error``, ``lost``, ``iou``, ``boxes``, ``reported``, ``confidence``)."""
    return score_frames(clip.truth, boxes, clip.source.size[0], rule=rule, reported=reported, vertices=vertices,
                        aspect=aspect, shown=shown, confidence=confidence)


def result_files(dirs, clips, fmt="otb"):
    """``(tracker name, clip, result file)`` for every result folder and clip: ``DIR/<clip name>.txt``
    (OTB) or ``DIR/<clip>/<clip>_001.txt`` (GOT-10k, VOT; :func:`~vistrack.io.results_format.find_result_file`,
    case-insensitive), the tracker named after ``DIR``. A missing file is a ``ValueError``; so are
    two folders of one name (they would be merged into one tracker) and a folder named like one
    of vistrack's algorithms or OpenCV trackers (it would be listed as that algorithm)."""
    out = []
    names = {}
    for d in dirs:
        d = Path(d)
        if d.name in names:
            raise ValueError(f"--results-dir {names[d.name]} and {d} have the same name {d.name!r}: each tracker is "
                             "named after its folder; rename one")
        names[d.name] = d
        if d.name.lower() in ALGORITHMS or is_baseline(d.name.lower()):
            raise ValueError(f"--results-dir {d} is named like vistrack's algorithm {d.name.lower()!r}: its results "
                             "would be listed as that algorithm's; rename the folder (e.g. after the tracker)")
        for c in clips:
            found = find_result_file(d, _name(c), fmt)
            if found is None:
                want = f"{_name(c)}.txt" if fmt == "otb" else f"{_name(c)}/{_name(c)}_001.txt"
                raise ValueError(f"--results-dir {d}: no result file {want} for clip {c} ({fmt} layout)")
            out.append((d.name, c, found))
    return out


def score_result_file(clip_path, path, name, fmt="otb"):
    """A task result, as :func:`run_task` writes, from another tracker's result file ``path``
    (``x,y,w,h`` per frame in format ``fmt``, :mod:`~vistrack.io.results_format`: OTB's 1-based, GOT-10k's
    and VOT's 0-based; ``0,0,0,0`` or NaN where it reports nothing — what ``vistrack run --results``
    writes), scored against the clip's ground truth under algorithm ``name``. Its frame rate is
    unknown (``ms`` empty)."""
    clip = load_clip(clip_path)
    try:
        boxes = read_result_file(path, fmt)
    except ValueError as e:
        raise VideoError(str(e)) from None
    if fmt == "vot" and len(boxes) and clip.truth is not None:  # its "1": initialised on the true box
        boxes[0] = _truth_boxes(clip.truth)[0]
    n = len(clip.truth["cx"])
    if len(boxes) != n:  # positional: a line per frame of the ground truth
        warnings.warn(f"{path} has {len(boxes)} lines for the {n} ground-truth frames of {_name(clip_path)}: "
                      + (f"the {n - len(boxes)} frames past its end are scored as not reported" if len(boxes) < n
                         else f"its last {len(boxes) - n} lines are ignored"), ResultsLengthWarning, stacklevel=2)
        boxes = np.concatenate([boxes[:n], np.full((max(0, n - len(boxes)), 4), np.nan)])
    result = score_boxes(clip, boxes)
    result.update({"clip": str(clip_path), "algo": name, "particles": 1, "run": 0, "ms": [],
                   "ess": [None] * result["frames"], "external": True})
    return result


def summarize(results):
    """Per clip × algo × N summaries of task results (:func:`vistrack.scoring.aggregate.summarize`; the
    comparison trackers marked as no particle filter)."""
    return metrics_summarize(results, not_filters=BASELINES)


class ResultsLengthWarning(UserWarning):
    """A result file and the ground truth differ in their number of frames."""


