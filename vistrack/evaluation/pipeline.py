"""``vistrack eval`` as one call: the configuration checked (:func:`eval_config`), the particle counts of
equal time (:func:`eval_equal_time`), then :func:`evaluate`: tasks -> grid -> load -> score ->
summarise -> write (``results.json``, ``results.csv``, plots and ``report.md``; with several targets the
MOT scores, :mod:`vistrack.reports.mot_report`). ``vistrack demo`` evaluates through it too.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass
from pathlib import Path

from .. import kernels
from ..batch.cluster import run_experiment
from ..batch.tasks import lock_out, task_path
from ..io.clips import find_clips, load_clip
from ..loop.stepper import filter_ms
from ..registry import (
    MODELS,
    OptionError,
    build_model,
    check_particle_memory,
    clip_model,
    get_model_spec,
    is_baseline,
    targets_model,
)
from ..registry.builders import start_frame
from ..reports.eval_report import write_eval_outputs
from ..reports.mot_report import write_mot_outputs
from ..scoring.metrics import equal_time
from ..scoring.mot import require_motmetrics
from ..system.compiling import compiling
from .experiment import (
    EvalConfig,
    check_algos,
    check_task_grid,
    result_files,
    score_result_file,
    summarize,
)
from .multi_target import plates_equal_time

__all__ = ["Evaluation", "eval_config", "eval_equal_time", "evaluate", "results_folder", "clips_model"]

#: the files ``eval`` writes into ``--out`` besides the task files
OUT_FILES = ("results.json", "results.csv", "report.md")


@dataclass
class Evaluation:
    """What :func:`evaluate` did: the summaries (per clip × algorithm × N; with several targets the MOT
    scores pooled per algorithm and N), the plots written, the report (``OUT/report.md``) and the
    particle counts of equal time (``{algo: N}``) or ``None``."""

    summaries: list
    plots: list
    report: Path
    chosen: dict | None = None
    #: the annotated videos written (``OUT/videos/<tracker>.mp4``)
    videos: list = dataclasses.field(default_factory=list)
    #: the other files written into ``OUT``, by name
    files: tuple = ("results.json", "results.csv", "report.md", "report.html")

    def wrote(self):
        """The line that names every file written: ``wrote OUT/results.json, results.csv, report.md,
        report.html, 6 plots and 3 annotated videos (videos/)``."""
        out = self.report.parent
        names = list(self.files[1:])
        counted = [f"{len(self.plots)} plot{'s' * (len(self.plots) != 1)}"] if self.plots else []
        if self.videos:
            counted.append(f"{len(self.videos)} annotated video{'s' * (len(self.videos) != 1)} (videos/)")
        *first, last = names + counted
        return f"wrote {out / self.files[0]}, {', '.join(first)} and {last}"


def clips_model(clips):
    """The model of ``eval`` without ``--model``, as ``run`` chooses it: the one the clips' ``meta.json``
    names, else the default; clips naming different models are a ``ValueError``."""
    named = {clip_model(load_clip(c).model_name) for c in clips}
    if len(named) > 1:
        raise ValueError(f"the clips name different models in meta.json ({', '.join(sorted(named))}): give --model")
    return named.pop()


def eval_config(clips, *, algos, particles, runs, seed, model=None, targets=None, results_dirs=()):
    """The :class:`~vistrack.evaluation.experiment.EvalConfig` of ``vistrack eval``, checked: the algorithms
    known and running on the model (:func:`~vistrack.evaluation.experiment.check_algos`), the clips found
    (:func:`~vistrack.io.clips.find_clips`), the model the clips name when none is given
    (:func:`clips_model`), one task's memory at every N, the task grid's memory
    (:func:`~vistrack.evaluation.experiment.check_task_grid`); with ``targets`` the plate model, the MOT
    scorer and each clip's ``objects.csv``. Raises :class:`~vistrack.registry.OptionError` for options
    that do not go together, ``ValueError`` (and ``VideoError``) for bad input; each one line."""
    if not particles or any(n < 1 for n in particles):
        raise ValueError("--particles needs positive integers")
    if not algos and not results_dirs:
        raise OptionError("nothing to evaluate: give --algos or --results-dir")
    check_algos(algos)
    clip_paths = find_clips(clips)
    if model is None and targets is None:
        model = clips_model(clip_paths)
    spec = get_model_spec(model if targets is None else targets_model(model))
    if targets is not None:
        _check_targets(model, clip_paths, results_dirs)
    check_algos(algos, spec.name, targets is not None)
    for a in algos:  # one task's working memory (tasks run side by side: one per worker)
        for n in ([] if is_baseline(a) else particles):
            check_particle_memory(n, spec.bytes_per_particle, a)
    # without algorithms (--algos "" with --results-dir) no particle count was used: none is recorded
    cfg = EvalConfig(clips=clip_paths, algos=list(algos), particles=list(particles) if algos else [], runs=runs,
                     seed=seed, model=model, targets=targets)
    check_task_grid(clip_paths, cfg.pairs(), runs)  # before equal time and the grid: one line, no work done
    return cfg


def _check_targets(model, clips, results_dirs):
    """``eval --targets``: the plate model, the MOT scorer installed, no result files, and objects.csv."""
    targets_models = [m for m, s in MODELS.items() if s.targets_class is not None]
    if model not in targets_models:
        raise OptionError(f"--targets is for --model {' or '.join(targets_models)}")
    try:
        require_motmetrics()
    except ImportError as e:
        raise ValueError(str(e)) from None
    if results_dirs:
        raise OptionError("--results-dir scores one box per frame: not with --targets")
    missing = [str(c) for c in clips if not (Path(c) / "objects.csv").is_file()]
    if missing:
        raise ValueError(f"{missing[0]} has no objects.csv (the per-plate ground truth of synth plate)")


def results_folder(out):
    """``out`` made and checked before the grid runs: one ``ValueError`` line where eval could not write
    its files (a file where ``tasks/`` goes, a folder where a file goes, no permission)."""
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"cannot create --out {out}: {e.strerror}") from None
    paths = [(task_path(out), True)] + [(out / n, False) for n in OUT_FILES]  # (path, a folder)
    blocked = next(((p, folder) for p, folder in paths if p.exists() and p.is_dir() != folder), None)
    if blocked is not None:  # found before the grid runs, not after
        raise ValueError(f"cannot write the results into {out}: {blocked[0]} is a "
                         f"{'folder' if blocked[0].is_dir() else 'file'}, where eval writes a "
                         f"{'folder' if blocked[1] else 'file'}")
    if not os.access(out, os.W_OK):
        raise ValueError(f"cannot write the results into {out}: permission denied")
    return out


def eval_equal_time(cfg, frames=30):
    """``{algo: N}``: N per algorithm for the time per frame of the first algorithm at the first N (thesis
    Tables 4.1, 4.3), timed on the first ``frames`` frames tracked of the first clip
    (:func:`~vistrack.scoring.metrics.equal_time`: a line through N and 2N, its slope at least a tenth of
    the time per particle at N, then up to three checks); with ``targets``, the several-plate timing
    (:func:`~vistrack.evaluation.multi_target.plates_equal_time`). A ``ValueError`` where the first clip is too
    short or an N would exceed the memory."""
    n_ref = cfg.particles[0]
    if cfg.targets is not None:
        return dict(plates_equal_time(cfg.clips[0], [(a, n_ref) for a in cfg.algos], cfg.targets)[0])
    clip = load_clip(cfg.clips[0])
    start = start_frame(clip, None, "")
    fr = []
    for i, f in clip.source:
        if i >= start + frames:
            break
        if i >= start:
            fr.append((i, f))
    if len(fr) < 3:
        raise ValueError(f"--equal-time times the algorithms on the first clip, {cfg.clips[0]}, which has "
                         f"{len(fr)} frame(s) to track: it needs at least 3")
    model = build_model(cfg.model, clip, init_gt="")
    entries, _ = equal_time(lambda a, n: filter_ms(fr, model, a, n), [(a, n_ref) for a in cfg.algos],
                            min_slope=0.1, checks=3)
    for algo, n in entries[1:]:
        try:
            check_particle_memory(n, get_model_spec(cfg.model).bytes_per_particle, algo)
        except ValueError:
            raise ValueError(f"--equal-time: {algo} would need N={n} for the time of {cfg.algos[0]} N={n_ref}, "
                             "more than memory allows; give a smaller --particles") from None
    return dict(entries)


def evaluate(cfg, out, *, results_dirs=(), results_format="otb", equal_time=False, on_equal_time=None,
             compiling_progress=None, **engine):
    """Evaluate ``cfg`` (an :class:`~vistrack.evaluation.experiment.EvalConfig`, :func:`eval_config`) into the
    folder ``out``: with ``equal_time`` the particle counts of equal time first (:func:`eval_equal_time`;
    ``on_equal_time(chosen)`` hears them before the grid runs), then the tasks on the grid
    (:func:`~vistrack.batch.cluster.run_experiment` with the ``engine`` options), the other trackers' result
    files in ``results_dirs`` scored beside them (format ``results_format``), the summaries, and the files
    (:func:`~vistrack.reports.eval_report.write_eval_outputs`; several targets:
    :func:`~vistrack.reports.mot_report.write_mot_outputs`). Returns an :class:`Evaluation`.

    Raises ``ValueError`` (one line) for an ``out`` that cannot take the results or result files that do
    not fit the clips, and what the grid raises; the task files finished are kept (``resume``).

    On local workers the kernels of the model and algorithms are compiled here first, once, telling
    ``compiling_progress(done, total)`` (:func:`~vistrack.system.compiling.compiling`: the first run after an
    install), rather than by every worker at once.
    """
    out = results_folder(out)
    if not engine.get("scheduler"):
        with compiling(compiling_progress, kernels.use()) as compiler:
            compiler.compile(cfg.model, cfg.algos, cfg.targets is not None)  # OpenCV's trackers: none
    chosen, run = None, cfg
    if equal_time:
        chosen = eval_equal_time(cfg)
        if on_equal_time:
            on_equal_time(chosen)
        run = dataclasses.replace(cfg, entries=list(chosen.items()))
    with lock_out(out):
        results = run_experiment(run, out, **engine)
        if cfg.targets is not None:
            return Evaluation(write_mot_outputs(out, cfg, results, cfg.targets, chosen), [], out / "report.md", chosen,
                              files=("results.json", "results.csv", "report.md"))
        results += [score_result_file(c, f, name, results_format)
                    for name, c, f in result_files(results_dirs, cfg.clips, results_format)]
        summaries = summarize(results)
        try:
            plots, videos = write_eval_outputs(out, cfg, summaries, results, chosen)
        except OSError as e:
            raise ValueError(f"cannot write the results into {out}: {e.strerror or e} (the task files are kept: "
                             "--resume writes them without running the tasks again)") from None
    return Evaluation(summaries, plots, out / "report.md", chosen, videos)
