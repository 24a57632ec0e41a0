"""``vistrack reproduce plate --overlap``: several plates at once (:mod:`vistrack.reproduce.multi_plate`)."""

from __future__ import annotations

import click

from vistrack.engine.evaluation import entries_config

from .options import check_writable
from .reproduce_common import _check_entries, _clip_suite, _report, _run

__all__ = ["overlap"]


def _require_scorer():
    """One error line, before any tracking, when the MOT scorer is missing."""
    from vistrack.core.mot import require_motmetrics

    try:
        require_motmetrics()
    except ImportError as e:
        raise click.ClickException(str(e)) from None


def overlap(clips_dir, make, frames, size, entries, runs, seed, targets, equal_time, quiet, json_path, engine,
            out_dir):
    """``reproduce plate --overlap``: several plates at once (:mod:`vistrack.reproduce.multi_plate`)."""
    from vistrack.data_synth.plate import make_plate_clip
    from vistrack.reproduce.multi_plate import (PlatesConfig, plates_equal_time, plates_results, plates_tasks,
                                                run_plates_task)

    _check_entries(entries)
    check_writable(json_path, "--json file")
    _require_scorer()
    clips = _clip_suite(clips_dir, "plate-overlap-clips", make, frames, size, make_plate_clip, "plate-overlap", quiet,
                        grid=(entries, runs), overlap=True, cars=6)
    if equal_time:
        entries, times = plates_equal_time(clips[0], entries, targets)
        click.echo("equal time: " + ", ".join(f"{a}:{n}" for a, n in entries) + " ("
                   + ", ".join(f"{k} {v:.1f} ms/frame" for k, v in times.items()) + ")")
    cfg = PlatesConfig(clips=clips, entries=entries, runs=runs, seed=seed, targets=targets)
    tasks = plates_tasks(cfg)
    out = _run(tasks, out_dir, "plates", runner=run_plates_task, **engine)
    try:
        results = plates_results(cfg, tasks, out)
    except ValueError as e:
        raise click.ClickException(str(e)) from None
    click.echo(f"{len(clips)} clips x {runs} runs, K = {targets} plate slots")
    _report("plates", {"results": results}, entries_config(cfg), json_path, None)
