"""The batch engine: a grid of tasks on Dask, with the ``--out`` lock, resume and task files.

An :class:`Experiment` (``eval``'s :class:`~vistrack.evaluation.experiment.EvalConfig`, each reproduction's
config) gives its tasks, the runner that does one and its results from the task files;
:func:`run_experiment` runs it: the tasks on :func:`run_grid`, then the results. A task is a JSON-ready dict; a runner
``runner(task, out_dir) -> path`` tracks it on a worker and writes its result JSON under
``out_dir/tasks`` (an experiment's ``runner``, e.g. :func:`vistrack.evaluation.experiment.run_task`). The
runner runs on the worker in a scratch folder of the worker's own and the result travels back to this process through
Dask, which writes ``OUT/tasks/<name>.json`` atomically: the workers need no filesystem in common
with the client, only the clips, which may be given as URLs (``http://``, ``s3://``, ...: see
:func:`vistrack.io.remote.fetch`) that every worker fetches itself.

A worker that dies (killed, out of memory) is replaced and its task runs again from its own seed
stream, so the results are those of an uninterrupted run; task files are only ever replaced whole,
so ``resume=True`` (``--resume``) runs only what is missing or stale.
"""

from __future__ import annotations

import json
import logging
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Protocol

from ..system.resources import worker_count
from .tasks import OutLocked, TaskFailed, check_shared, lock_out, stale_tasks, task_done, task_path, write_atomic

__all__ = ["Experiment", "run_experiment", "EngineError", "open_client", "dask_quiet", "run_grid", "run_on_worker",
           "OutLocked", "TaskFailed"]


class Experiment(Protocol):
    """What :func:`run_experiment` runs: ``eval``'s evaluation and each reproduction."""

    #: ``runner(task, out_dir) -> path``: one task on a worker, its result written under ``out_dir``
    #: (:func:`~vistrack.batch.tasks.save_result`); a module-level function (it travels to the workers)
    runner: Callable

    def tasks(self):
        """The experiment's tasks: JSON-ready dicts, each with its unique ``name``."""

    def results(self, tasks, out_dir):
        """The experiment's results from the task files of ``tasks`` in ``out_dir``
        (:func:`~vistrack.batch.tasks.load_task_results`)."""


class EngineError(RuntimeError):
    """The grid cannot start: no scheduler at the address, or one without workers."""


def open_client(scheduler=None, workers=0, timeout=10, in_process=False):
    """``(client, cluster)``: a ``distributed.Client`` of the scheduler at ``scheduler`` (``cluster``
    ``None``), or of a new ``LocalCluster`` of ``workers`` processes (0: one per core; threads of this
    process with ``in_process``). Raises :class:`EngineError` with one line."""
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler, timeout=f"{timeout}s")
        except (OSError, TimeoutError, ValueError) as e:
            raise EngineError(f"cannot reach the Dask scheduler at {scheduler} within {timeout} s ({e}); "
                              "give its address as tcp://host:8786") from None
        try:
            client.wait_for_workers(1, timeout=timeout)
        except TimeoutError:
            client.close()
            raise EngineError(f"the Dask scheduler at {scheduler} has no workers (waited {timeout} s)") from None
        return client, None
    # the HTTP server on any free local port (not 8787, which another cluster may hold: a warning);
    # workers ignore Ctrl-C, which this process handles (vistrack.evaluation.experiment.dask_setup)
    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                           processes=not in_process, dashboard_address=None, silence_logs=logging.CRITICAL,
                           scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                           **({} if in_process else {"preload": ["vistrack.evaluation.experiment"]}))
    return Client(cluster), cluster


class WorkerDeaths(logging.Handler):
    """Counts the worker processes the nannies restart."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.count = 0

    def emit(self, record):
        self.count += "Restarting worker" in record.getMessage()


@contextmanager
def dask_quiet():
    """distributed's log lines (a lost worker, keys rescheduled) kept from the user for the block:
    what matters arrives as an exception (:class:`TaskFailed`) or, for a worker that died and was
    replaced, as a count. Yields the :class:`WorkerDeaths` counter."""
    loggers = [logging.getLogger(n) for n in ("distributed", "distributed.client", "distributed.nanny")]
    saved = [(lg.level, lg.propagate) for lg in loggers]
    deaths = WorkerDeaths()
    for lg in loggers[:2]:
        lg.setLevel(logging.CRITICAL)
    loggers[2].setLevel(logging.WARNING)
    loggers[2].propagate = False
    loggers[2].addHandler(deaths)
    try:
        yield deaths
    finally:
        loggers[2].removeHandler(deaths)
        for lg, (level, propagate) in zip(loggers, saved):
            lg.setLevel(level)
            lg.propagate = propagate


def run_on_worker(runner, task):
    """On a worker: ``runner(task, scratch)`` in a scratch folder of the worker's own; returns the
    result file's text (the client writes it into ``--out``)."""
    with tempfile.TemporaryDirectory(prefix="vistrack-task-") as scratch:
        path = runner(task, scratch)
        return Path(path).read_text()


def execute(tasks, out_dir, client, *, resume=False, progress=None, key_prefix="vistrack", runner=None):
    """Run the tasks not yet done on ``client``; each result comes back through Dask and is written
    here to ``out_dir/tasks/<name>.json`` (atomically). Returns the number of tasks run.

    A task whose workers keep dying, or that fails on a broken file (``OSError``, ``VideoError``),
    raises :class:`TaskFailed` naming it. ``progress(k)`` is called as tasks finish (and once for
    those skipped on resume).
    """
    from distributed import KilledWorker, as_completed

    from ..io.video import VideoError

    pending = [t for t in tasks if not (resume and task_done(t, out_dir))]
    if progress and len(tasks) > len(pending):
        progress(len(tasks) - len(pending))
    if runner is None:
        raise TypeError("execute needs the experiment's runner (runner=...): what a worker does with one task")
    task_path(out_dir).mkdir(parents=True, exist_ok=True)
    futs = {client.submit(run_on_worker, runner, t, key=f"{key_prefix}-{t['name']}", retries=2, pure=False): t
            for t in pending}
    for f in as_completed(list(futs)):
        name = futs[f]["name"]
        try:
            text = f.result()
        except KilledWorker as e:
            raise TaskFailed(f"task {name} ended the process of every worker that ran it ({e.allowed_failures + 1}; "
                             "out of memory?); the finished task files are kept: --resume runs the rest") from None
        except (OSError, VideoError) as e:
            raise TaskFailed(f"task {name} failed: {e}; the finished task files are kept: "
                             "--resume runs the rest") from None
        try:
            json.loads(text)  # whole JSON, or the task failed
        except ValueError:
            raise TaskFailed(f"task {name} returned a damaged result; the finished task files are kept: "
                             "--resume runs the rest") from None
        write_atomic(task_path(out_dir, futs[f]), text)
        if progress:
            progress(1)
    return len(pending)


def run_grid(tasks, out, *, scheduler=None, workers=0, timeout=10, in_process=False, resume=False, progress=None,
             runner=None, notify=None, on_ready=None):
    """Execute ``tasks`` on Dask (a LocalCluster unless ``scheduler``), holding the ``out`` lock
    (:func:`~vistrack.batch.tasks.lock_out`); the task files are written into ``out/tasks`` here.

    ``on_ready(number of tasks)`` once the workers are there; ``progress(k)`` as tasks finish; ``notify(line)`` for
    what the user should hear even when quiet
    (stale task files on resume, workers that died and were replaced). Raises :class:`OutLocked`,
    :class:`EngineError` or :class:`TaskFailed` with one line each; the files finished so far are kept.
    """
    notify = notify or (lambda line: None)
    with lock_out(out):
        if resume:
            stale = stale_tasks(tasks, out)
            if stale:
                notify(f"--resume: {len(stale)} of {len(tasks)} task files come from other options, seed, clip "
                       "content or vistrack version or code (or are damaged): running them again")
            if all(task_done(t, out) for t in tasks):
                return
        if not scheduler:  # no more workers than the machine and the tasks can use
            workers, capped = worker_count(workers, len(tasks))
            if capped:
                notify(capped)
        with dask_quiet() as deaths:
            client, cluster = open_client(scheduler, workers, timeout, in_process)
            try:
                if scheduler:  # local clip paths must be the workers' too (URLs each worker fetches)
                    check_shared(client, tasks)
                if on_ready:
                    on_ready(len(tasks))
                execute(tasks, out, client, resume=resume, progress=progress, runner=runner)
            finally:
                client.close()
                if cluster is not None:
                    cluster.close()
        if deaths.count:
            notify(f"note: {deaths.count} worker process(es) died and were replaced; their tasks ran again from "
                   "their own seeds (the results are those of an uninterrupted run)")


def run_experiment(experiment, out, **engine):
    """``experiment``'s tasks on the grid (:func:`run_grid` with its runner and the ``engine`` options:
    ``scheduler``, ``workers``, ``timeout``, ``in_process``, ``resume``, ``progress``, ``notify``,
    ``on_ready``) into the folder ``out`` (made), then its results from the task files
    (``experiment.results``), all under the ``out`` lock. Raises ``ValueError`` for a folder that cannot
    be made, and what :func:`run_grid` raises."""
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"cannot create --out folder {out}: {e.strerror}") from None
    tasks = experiment.tasks()
    with lock_out(out):
        if tasks:
            run_grid(tasks, out, runner=experiment.runner, **engine)
        return experiment.results(tasks, out)
