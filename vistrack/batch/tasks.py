"""The engine's task files: one JSON file per task under ``OUT/tasks``, written whole, with a
fingerprint of everything that determines it (what ``--resume`` checks), executed on Dask, and
one experiment per ``--out`` folder (a lock)."""

from __future__ import annotations

import json
import os
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..io.outputs import replacing

__all__ = ["task_path", "result_digest", "task_fingerprint", "write_task_result", "save_result", "write_atomic",
           "task_done", "stale_tasks", "load_task_results", "TaskFailed", "check_shared", "OutLocked", "lock_out"]


def task_path(out_dir, task=None):
    """``out_dir/tasks/<name>.json``, the file of ``task`` (a dict with its ``name``); without ``task``,
    the folder ``out_dir/tasks`` that holds them."""
    folder = Path(out_dir) / "tasks"
    return folder if task is None else folder / f"{task['name']}.json"


def _clip_signature(clip):
    """Name, size and modification time of the files of a clip (its folder, or a video file's
    folder): a changed video or ground truth changes the signature. A clip given by URL is signed
    by its URL (each worker fetches its own copy)."""
    if "://" in str(clip):
        return [("url", str(clip))]
    p = Path(clip)
    folder = p if p.is_dir() else p.parent
    out = []
    try:
        for e in sorted(os.scandir(folder), key=lambda e: e.name):
            if e.is_file():
                st = e.stat()
                out.append((e.name, st.st_size, st.st_mtime_ns))
            elif e.is_dir():
                out.append((e.name + "/", len(os.listdir(e.path)), e.stat().st_mtime_ns))
    except OSError:
        pass
    return out


def _jsonable(v):
    if isinstance(v, np.random.SeedSequence):
        return {"entropy": str(v.entropy), "spawn_key": list(v.spawn_key)}
    if isinstance(v, dict):
        return {k: _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, (np.integer, np.floating)):
        return v.item()
    return v if isinstance(v, (int, float, str, bool, type(None))) else str(v)


def code_signature():
    """A hash of vistrack's own source (every ``.py`` file of the installed package, by path and
    content): an edited model or filter changes it where the version string does not (an editable
    install, a checkout between releases). Computed once per process."""
    global _CODE
    if _CODE is None:
        import hashlib

        root = Path(__file__).resolve().parents[1]  # the package, not this module's folder alone
        h = hashlib.sha256()
        for p in sorted(root.rglob("*.py")):
            h.update(p.relative_to(root).as_posix().encode() + b"\0" + p.read_bytes() + b"\0")
        _CODE = h.hexdigest()[:16]
    return _CODE


_CODE = None


def task_fingerprint(task):
    """A hash of everything that determines a task's result: the task itself (algorithm, N, model,
    run, seed stream, config), the content signature of its clip, the vistrack version and its
    source (:func:`code_signature`: a result computed before a change of the code — a report rule,
    a default — is not silently reused). A result file whose fingerprint differs is not reused by
    ``--resume``."""
    import hashlib

    from .. import __version__

    body = {"task": _jsonable(task), "version": __version__, "code": code_signature()}
    if "clip" in task:
        body["clip_files"] = _clip_signature(task["clip"])
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()[:20]


def result_digest(result):
    """A hash of a task's result as its file holds it (its keys and every value, without ``fingerprint``
    and ``digest``): a file cut short, edited or damaged whose fingerprint survived is told apart."""
    import hashlib

    body = {k: v for k, v in result.items() if k not in ("fingerprint", "digest")}
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()[:20]


def write_task_result(path, result, task=None):
    """Write a task's result JSON atomically (temporary file, then rename); return the path.
    With ``task``, the result records its :func:`task_fingerprint` and its :func:`result_digest` (what
    ``--resume`` checks)."""
    path = Path(path)
    if task is not None:
        result = {**result, "fingerprint": task_fingerprint(task)}
        result["digest"] = result_digest(result)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, json.dumps(result))
    return str(path)


def save_result(out_dir, task, result):
    """A runner's result of ``task`` written to its file under ``out_dir`` (:func:`task_path`), with the
    task's fingerprint (:func:`write_task_result`); returns the path."""
    return write_task_result(task_path(out_dir, task), result, task)


def write_atomic(path, text, what="file"):
    """Write ``text`` to ``path`` whole or not at all (:func:`vistrack.io.outputs.replacing`: a
    temporary file beside it, renamed over ``path`` once written and closed; a crash or a full
    disk leaves the old file, never half of the new one, and the error names ``path``). A device
    or pipe such as ``/dev/stdout`` is written directly."""
    with replacing(path, what) as tmp:
        Path(tmp).write_text(text)


def task_done(task, out_dir):
    """Whether ``task``'s result file exists, parses, was computed by this very task (its
    :func:`task_fingerprint`: same clip content, options, seed stream, version and code) and holds what
    that task wrote (its :func:`result_digest`: no key lost, no list cut short, no value changed) — what
    ``--resume`` may reuse."""
    p = task_path(out_dir, task)
    if not p.is_file():
        return False
    try:
        data = json.loads(p.read_text())
    except (json.JSONDecodeError, OSError, UnicodeDecodeError, RecursionError):
        return False
    return (isinstance(data, dict) and data.get("fingerprint") == task_fingerprint(task)
            and data.get("digest") == result_digest(data))


def stale_tasks(tasks, out_dir):
    """The tasks whose result file exists but cannot be reused (another configuration, or damaged)."""
    return [t for t in tasks if task_path(out_dir, t).is_file() and not task_done(t, out_dir)]


def load_task_results(tasks, out_dir):
    """The result dicts of ``tasks`` (list of task dicts), read from their files (:func:`task_path`), in the
    tasks' order: what every experiment's results are computed from. A file that does not parse or does
    not hold what its task wrote (:func:`result_digest`) is :class:`TaskFailed` naming it."""
    out = []
    for t in tasks:
        p = task_path(out_dir, t)
        try:
            data = json.loads(p.read_text())
        except (OSError, ValueError, RecursionError) as e:
            raise TaskFailed(f"task file {p} cannot be read ({e}); run again with --resume to redo it") from None
        if not isinstance(data, dict) or ("digest" in data and data["digest"] != result_digest(data)):
            raise TaskFailed(f"task file {p} was changed or damaged after its task wrote it; run again with "
                             "--resume to redo it")
        out.append(data)
    return out


class TaskFailed(RuntimeError):
    """A task of the grid could not finish (its workers died, or it met a broken input file); the
    task files finished so far are kept, so ``--resume`` runs only the rest."""


def _unseen(paths):
    """On a worker: the ``paths`` (as the tasks give them) it cannot see."""
    return [p for p in paths if not os.path.exists(p)]


def check_shared(client, tasks):
    """Raise ``TaskFailed`` unless every worker of ``client`` sees the tasks' clips at the paths the
    tasks give (clips given as URLs are fetched by each worker and not checked; the results come back
    through Dask, so no worker needs ``--out``)."""
    clips = sorted({t["clip"] for t in tasks if "clip" in t and "://" not in str(t["clip"])})
    missing = {w: m for w, m in client.run(_unseen, clips).items() if m}
    if missing:
        worker, paths = next(iter(missing.items()))
        raise TaskFailed(f"{len(missing)} worker(s) of the scheduler (e.g. {worker}) cannot see clip {paths[0]}: give "
                         "the clips at paths the workers share, or as URLs they can fetch (http://, s3://, ...)")


class OutLocked(RuntimeError):
    """Another running process holds the ``--out`` folder."""


@contextmanager
def lock_out(out_dir):
    """Hold ``out_dir/.vistrack.lock`` (pid and host) for the block: one experiment per ``--out``.

    Raises :class:`OutLocked` (one line naming the holder) when a live process holds it; a lock
    left by a dead process on this host is taken over. Re-entrant within a process.
    """
    import socket

    path = Path(out_dir) / ".vistrack.lock"
    me = f"{os.getpid()}@{socket.gethostname()}"
    try:
        fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        holder = path.read_text().strip() if path.is_file() else ""
        if holder == me:
            yield
            return
        pid, _, host = holder.partition("@")
        alive = True
        if host == socket.gethostname() and pid.isdigit():
            try:
                os.kill(int(pid), 0)
            except ProcessLookupError:
                alive = False
            except PermissionError:
                pass
        if alive:
            raise OutLocked(f"{out_dir} is in use by another vistrack process ({holder}); wait for it or "
                            f"choose another --out (remove {path} if that process is gone)") from None
        path.unlink(missing_ok=True)
        fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    with os.fdopen(fd, "w") as f:
        f.write(me)
    try:
        yield
    finally:
        path.unlink(missing_ok=True)
