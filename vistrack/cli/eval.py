"""``vistrack eval``: algorithms × particle counts × runs over clips, on Dask."""

from __future__ import annotations

import os
from pathlib import Path

import click
import numpy as np

from vistrack.engine.evaluation import (OPENCV_TRACKERS, EvalConfig, check_algos, find_clips,
                                 load_task_results, result_files, score_result_file, summarize, task_list)
from vistrack.engine.report import write_eval_outputs
from vistrack.registry import DEFAULT_MODEL, MODELS, all_algos, clip_model, default_comparison, get_model_spec
from vistrack.io.clips import load_clip
from vistrack.io.results_format import FORMATS
from vistrack.core.metrics import equal_time_n
from vistrack.core.runtime import check_particle_memory
from vistrack.io.video import VideoError

from .grid import _locked, run_tasks
from .options import SEED, IntList, StrList

__all__ = ["eval_cmd"]

def _equal_time(cfg, clips, frames=30):
    """N per algorithm for the time per frame of the first algorithm at the first N (thesis Tables 4.1, 4.3)."""
    import time

    from vistrack.registry import build_model
    from vistrack.io.clips import load_clip
    from vistrack.filters import make_filter
    from vistrack.track.loop import track

    from vistrack.registry.builders import start_frame
    from vistrack.core.runtime import check_particle_memory

    clip = load_clip(clips[0])
    start = start_frame(clip, None, "")
    fr = []
    for i, f in clip.source:
        if i >= start + frames:
            break
        if i >= start:
            fr.append((i, f))
    if len(fr) < 3:
        raise click.ClickException(f"--equal-time times the algorithms on the first clip, {clips[0]}, which has "
                                   f"{len(fr)} frame(s) to track: it needs at least 3")
    model = build_model(cfg.model, clip, init_gt="")
    bpp = get_model_spec(cfg.model).bytes_per_particle

    def ms(algo, n):
        best = np.inf
        for _ in range(2):
            t0 = time.perf_counter()
            for _ in track(fr, make_filter(algo, model), n, np.random.default_rng(0)):
                pass
            best = min(best, (time.perf_counter() - t0) * 1e3 / len(fr))
        return best

    n_ref = cfg.particles[0]
    budget = ms(cfg.algos[0], n_ref)
    chosen = {cfg.algos[0]: n_ref}
    for algo in cfg.algos[1:]:
        n = equal_time_n(lambda k: ms(algo, k), n_ref, budget, min_slope=0.1, checks=3)[0]
        try:
            check_particle_memory(n, bpp, algo)
        except ValueError:
            raise click.ClickException(f"--equal-time: {algo} would need N={n} for the time of {cfg.algos[0]} "
                                       f"N={n_ref}, more than memory allows; give a smaller --particles") from None
        chosen[algo] = n
    return chosen


def _eval_targets(cfg, targets, equal_time, results_dirs, out, engine):
    """``eval --targets K``: several plates at once, scored by MOTA and IDF1 (:mod:`vistrack.engine.mot_report`)."""
    from vistrack.engine.mot_report import write_mot_outputs
    from vistrack.reproduce.multi_plate import plates_equal_time, run_plates_task, score_plates_tasks

    from .reproduce_plates import _require_scorer

    if cfg.model != "plate":
        raise click.UsageError("--targets is for --model plate")
    _require_scorer()
    if results_dirs:
        raise click.UsageError("--results-dir scores one box per frame: not with --targets")
    missing = [str(c) for c in cfg.clips if not (Path(c) / "objects.csv").is_file()]
    if missing:
        raise click.ClickException(f"{missing[0]} has no objects.csv (the per-plate ground truth of synth plate)")
    chosen = None
    if equal_time:
        entries, _ = plates_equal_time(cfg.clips[0], [(a, cfg.particles[0]) for a in cfg.algos], targets)
        chosen = dict(entries)
        if not engine["quiet"]:
            click.echo("equal time per frame: " + ", ".join(f"{a} N={n}" for a, n in chosen.items()))
        cfg = EvalConfig(**{**cfg.__dict__, "entries": entries})
    tasks = task_list(cfg, cfg.clips)
    for t in tasks:
        t["targets"] = targets
    with _locked(out):
        run_tasks(tasks, out, desc="eval", runner=run_plates_task, **engine)
        try:
            rows = score_plates_tasks(tasks, out)
        except ValueError as e:
            raise click.ClickException(str(e)) from None
        write_mot_outputs(out, cfg, rows, targets, chosen)
    if not engine["quiet"]:
        click.echo((out / "report.md").read_text().split("\n\n## Per clip")[0].split("## Averages over clips\n\n")[-1])
        click.echo(f"wrote {out / 'results.json'}, results.csv and report.md")


def _results_folder(out_dir):
    """``--out`` made and checked before the grid runs: one error line where eval could not write its
    files (a file where ``tasks/`` goes, a folder where a file goes, no permission)."""
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise click.ClickException(f"cannot create --out {out}: {e.strerror}") from None
    blocked = next((out / n for n in ("tasks", "results.json", "results.csv", "report.md")
                    if (out / n).exists() and (out / n).is_dir() != (n == "tasks")), None)
    if blocked is not None:  # found before the grid runs, not after
        raise click.ClickException(f"cannot write the results into {out}: {blocked} is a "
                                   f"{'folder' if blocked.is_dir() else 'file'}, where eval writes a "
                                   f"{'folder' if blocked.name == 'tasks' else 'file'}")
    if not os.access(out, os.W_OK):
        raise click.ClickException(f"cannot write the results into {out}: permission denied")
    return out


def _clips_model(clips):
    """The model of ``eval`` without ``--model``, as ``run`` chooses it: the one the clips' ``meta.json``
    names, else the default; clips naming different models need ``--model``."""
    named = {clip_model(load_clip(c).model_name) for c in clips}
    if len(named) > 1:
        raise ValueError(f"the clips name different models in meta.json ({', '.join(sorted(named))}): give --model")
    return named.pop()


@click.command("eval")
@click.argument("clips", nargs=-1, required=True, type=click.Path())
@click.option("--algos", default=",".join(default_comparison()), show_default=True, type=StrList(),
              help="Algorithms, any that run takes on the model (" + ", ".join(all_algos()) + ") and OpenCV "
                   "trackers (" + ", ".join(OPENCV_TRACKERS) + "; KCF and CSRT need opencv-contrib-python-headless).")
@click.option("--particles", default="100,750", show_default=True, type=IntList(), help="Particle counts N.")
@click.option("--runs", default=20, show_default=True, type=click.IntRange(min=1), help="Runs per clip × algo × N.")
@click.option("--seed", default=0, show_default=True, type=SEED,
              help="Random seed: the same seed gives the same output, bit for bit.")
@click.option("--model", default=None, metavar="[" + "|".join(MODELS) + "]",
              help="Tracking model, any registered one, started from the first ground-truth box [default: as run: "
                   "the model the clips' meta.json names (synthetic clips), else " + DEFAULT_MODEL + ", any object, "
                   "appearance learned from the first frame]. plate: layout from the box's aspect.")
@click.option("--equal-time", is_flag=True, help="Pick N per algorithm for equal CPU time per frame.")
@click.option("--targets", type=click.IntRange(min=1), default=None,
              help="Plate model: track up to K plates at once (no start box; partitioned-lis, partitioned, "
                   "branched-partitioned(-lis), lis, bootstrap) and score MOTA and IDF1 against each clip's "
                   "objects.csv (synth plate).")
@click.option("--scheduler", help="Address of a running Dask scheduler (tcp://host:8786) [default: a LocalCluster].")
@click.option("--workers", default=0, show_default=True, type=click.IntRange(min=0),
              help="LocalCluster worker processes (0: one per core).")
@click.option("--timeout", default=10, show_default=True, type=click.IntRange(min=1),
              help="Seconds to wait for --scheduler.")
@click.option("--in-process", is_flag=True, help="LocalCluster workers as threads of this process (debugging, tests).")
@click.option("--resume", is_flag=True, help="Keep finished task files in --out and run only the rest.")
@click.option("--results-dir", "results_dirs", multiple=True, type=click.Path(exists=True, file_okay=False),
              help="Score another tracker's result files beside vistrack's: DIR/<clip name>.txt per clip (OTB) or "
                   "DIR/<clip>/<clip>_001.txt (GOT-10k, VOT), x,y,w,h per frame (0,0,0,0 for none; what run "
                   "--results writes); named after DIR. Repeat for several trackers; --algos '' scores only these.")
@click.option("--results-format", "results_format", type=click.Choice(FORMATS), default="otb", show_default=True,
              help="Format of the --results-dir files: otb (1-based pixels, as the OTB toolkit and pytracking write "
                   "them), got10k or vot (0-based).")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False), help="Results folder.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar; print only errors.")
def eval_cmd(clips, algos, particles, runs, seed, model, equal_time, targets, scheduler, workers, timeout, in_process,
             resume, results_dirs, results_format, out_dir, quiet):
    """Evaluate algorithms over CLIPS (clip folders, videos with ground truth, or folders of clip folders).

    Every clip × algorithm × N × run is one Dask task writing its own file
    under OUT/tasks, so --resume continues an interrupted evaluation. Writes
    OUT/results.json, OUT/results.csv (one row per task), PNG plots and
    OUT/report.md.
    """
    if any(n < 1 for n in particles) or not particles:
        raise click.ClickException("--particles needs positive integers")
    if not algos and not results_dirs:
        raise click.UsageError("nothing to evaluate: give --algos or --results-dir")
    try:
        check_algos(algos)
        clip_paths = find_clips(clips)
        if model is None and targets is None:
            model = _clips_model(clip_paths)
        spec = get_model_spec(model or "plate")
        check_algos(algos, spec.name if targets is None or model == "plate" else None, targets is not None)
        for a in algos:  # one task's working memory (tasks run side by side: one per worker)
            for n in ([] if a in OPENCV_TRACKERS else particles):
                check_particle_memory(n, spec.bytes_per_particle, a)
    except (ValueError, VideoError) as e:
        raise click.ClickException(str(e)) from None
    out = _results_folder(out_dir)
    # without algorithms (--algos "" with --results-dir) no particle count was used: none is recorded
    cfg = EvalConfig(clips=clip_paths, algos=list(algos), particles=list(particles) if algos else [], runs=runs,
                     seed=seed, model=model)
    engine = dict(scheduler=scheduler, workers=workers, timeout=timeout, in_process=in_process, resume=resume,
                  quiet=quiet)
    if targets is not None:
        return _eval_targets(cfg, targets, equal_time, results_dirs, out, engine)
    chosen = None
    tasks = task_list(cfg, clip_paths)
    if equal_time:
        chosen = _equal_time(cfg, clip_paths)
        if not quiet:
            click.echo("equal time per frame: " + ", ".join(f"{a} N={n}" for a, n in chosen.items()))
        tasks = task_list(EvalConfig(**{**cfg.__dict__, "entries": list(chosen.items())}), clip_paths)
    with _locked(out):
        if tasks:
            run_tasks(tasks, out, scheduler=scheduler, workers=workers, timeout=timeout, in_process=in_process,
                      resume=resume, quiet=quiet, desc="eval")
        results = load_task_results(tasks, out)
        try:
            results += [score_result_file(c, f, name, results_format)
                        for name, c, f in result_files(results_dirs, clip_paths, results_format)]
        except (ValueError, VideoError) as e:
            raise click.ClickException(str(e)) from None
        summaries = summarize(results)
        try:
            plots = write_eval_outputs(out, cfg, summaries, results, chosen)
        except OSError as e:
            raise click.ClickException(f"cannot write the results into {out}: {e.strerror or e} (the task files "
                                       "are kept: --resume writes them without running the tasks again)") from None
    if not quiet:
        click.echo((out / "report.md").read_text().split("\n\n## Per clip")[0].split("## Averages over clips\n\n")[-1])
        click.echo(f"wrote {out / 'results.json'}, results.csv, report.md and {len(plots)} plots")
