"""The output-path layer: every file a run writes goes through here.

* :func:`same_file`: two names of one file, by identity (``st_dev``, ``st_ino``), not by
  spelling: a hard link, a symbolic link or ``./x`` against ``x``.
* :func:`check_writable`: whether a file can be written at a path, before any work.
* :func:`input_files`: the files a run reads from a video, clip or image folder (what an output
  must never be).
* :class:`OutputLock`: one live writer per output. A lock file ``.NAME.lock`` beside the output,
  held with ``flock`` (released by the kernel when the process ends, however it ends): a second
  run given the same output refuses it with one line (:class:`OutputBusy`).
* :func:`temporary_name`: a name beside the output that no other file has (created
  exclusively), so two writers can never share a temporary file; the writer renames it over
  the output when done (:func:`os.replace`, atomic within a folder).
* :func:`replacing`: that rule for a file written at once. An output is replaced only by a
  complete file: renamed over the output after its last write, flush and close succeeded; on
  any failure the temporary file is removed, the earlier output is left as it was, and
  :class:`OutputError` names the output (never the temporary file) and the cause.
"""

from __future__ import annotations

import errno
import os
from contextlib import contextmanager
from pathlib import Path

from .clip_files import CLIP_FILES, FRAME_FOLDERS

__all__ = ["OutputBusy", "OutputError", "same_file", "file_id", "check_writable", "input_files", "OutputLock",
           "temporary_name", "is_device", "replacing", "left_note"]


class OutputBusy(RuntimeError):
    """Another live process writes this output."""


class OutputError(OSError):
    """An output could not be written whole (a full disk, a failed flush or close).

    ``errno``, ``strerror`` are the cause's, ``filename`` the output the user gave (never its
    temporary file); ``str()`` is one line: what, where, why, and what is left at that name.

    Parameters
    ----------
    what : str
        What the output is ("annotated video", "track file", ...).
    path : str or Path
        The output.
    cause : BaseException
        Why it failed.
    left : str
        What is left at ``path`` ("the earlier t.csv is kept", ...).
    """

    def __init__(self, what, path, cause, left=""):
        errno_, strerror = (cause.errno, cause.strerror) if isinstance(cause, OSError) else (None, None)
        super().__init__(errno_, strerror or str(cause) or type(cause).__name__, str(path))
        self.what, self.left = what, left

    def __str__(self):
        return f"cannot write the {self.what} {self.filename}: {self.strerror}" + (f"; {self.left}" if self.left
                                                                                    else "")


def left_note(path, earlier):
    """What a failed write leaves at ``path``: the earlier file (``earlier``: it existed), or nothing."""
    name = Path(path).name
    return f"the earlier {name} is kept" if earlier else f"no {name} was written"


@contextmanager
def replacing(path, what="file", tag="tmp"):
    """Write ``path`` whole or not at all: yields a temporary path beside it
    (:func:`temporary_name`) for the block to write and close; when the block succeeds it is
    renamed over ``path``; when anything fails it is removed, ``path`` is left as it was and
    :class:`OutputError` names ``path`` and the cause (an ``OSError``; other errors pass as
    they are). A device (``/dev/stdout``) is yielded itself and written directly."""
    path = Path(path)
    if is_device(path):
        yield path
        return
    earlier = path.is_file()
    tmp = temporary_name(path, tag)
    try:
        yield tmp
        os.replace(tmp, path)
    except OutputError:
        raise
    except OSError as e:
        raise OutputError(what, path, e, left_note(path, earlier)) from None
    finally:
        tmp.unlink(missing_ok=True)


def file_id(path):
    """``(st_dev, st_ino)`` of an existing file, or ``None``."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (st.st_dev, st.st_ino)


def check_writable(path, what, create=False):
    """Raise ``ValueError`` (one line, naming it ``what``) unless a file can be written at ``path``: not a
    folder, in a folder that exists (``create``: or can be made: the nearest existing one a folder), with
    permission. ``None`` passes."""
    if path is None:
        return
    path = os.path.abspath(path)
    parent = os.path.dirname(path)
    if os.path.isdir(path):
        raise ValueError(f"{what} {path} is a directory, not a file")
    while create and not os.path.exists(parent):
        parent = os.path.dirname(parent)
    if os.path.exists(parent) and not os.path.isdir(parent):
        raise ValueError(f"cannot write {what} {path}: {parent} is a file, not a folder")
    if not os.path.isdir(parent):
        raise ValueError(f"cannot write {what} {path}: folder {parent} does not exist")
    if not os.access(parent, os.W_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        raise ValueError(f"cannot write {what} {path}: permission denied")


def same_file(a, b):
    """Whether ``a`` and ``b`` name one existing file (:func:`os.path.samefile`; ``False`` when
    either does not exist)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def is_device(path):
    """Whether ``path`` exists and is not a regular file or folder (``/dev/null``, a pipe): such
    outputs are written directly and may be shared."""
    p = Path(path)
    return p.exists() and not p.is_file() and not p.is_dir()


def input_files(video, extra=()):
    """The regular files a run of ``video`` (a video file, an image folder or a clip folder) may
    read, plus ``extra`` (a template, an ``--init-gt`` file): the video itself, its folder's
    ground truth and ``meta.json``, every file of ``img/`` and ``color/`` and the folder's own
    files. Used to refuse an output that is one of them (by identity, :func:`file_id`)."""
    p = Path(video)
    folder = p if p.is_dir() else p.parent
    out = [p] if p.is_file() else []
    out += [folder / n for n in CLIP_FILES]
    if p.is_dir():
        for sub in (folder, *(folder / f for f in FRAME_FOLDERS)):
            try:
                out += [e for e in sub.iterdir() if e.is_file()]
            except OSError:
                pass
    out += [Path(e) for e in extra if e]
    return [q for q in out if q.is_file()]


def temporary_name(path, tag="part"):
    """Create (exclusively) and return an empty file beside ``path`` that no other writer holds:
    ``NAME.part`` when free, else ``NAME.<pid>-<k>.part``; the suffix of ``path`` is kept at the
    end for writers that pick the format from it (``tag="part"`` with ``a.mp4`` gives
    ``.a.part.mp4``, ``.a.<pid>-<k>.part.mp4``)."""
    path = Path(path)
    keep_suffix = path.suffix.lower() in (".mp4", ".avi", ".mov", ".mkv", ".m4v")
    for k in range(1000):
        extra = "" if k == 0 else f".{os.getpid()}-{k}"
        name = f".{path.stem}{extra}.{tag}{path.suffix}" if keep_suffix else f"{path.name}{extra}.{tag}"
        cand = path.with_name(name)
        try:
            fd = os.open(cand, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        return cand
    raise OSError(errno.EEXIST, "no free temporary name", str(path))


class OutputLock:
    """Hold ``.NAME.lock`` beside ``path`` with an exclusive ``flock`` until :meth:`release`:
    one live writer per output. :class:`OutputBusy` when another process holds it. A device
    (``/dev/null``) is not locked."""

    def __init__(self, path, what="output"):
        self.path = Path(path)
        self.lock = None
        self._fd = None
        if is_device(self.path):
            return
        import fcntl

        lock = self.path.with_name(f".{self.path.name}.lock")
        for _ in range(20):
            fd = os.open(lock, os.O_CREAT | os.O_RDWR, 0o666)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                os.close(fd)
                holder = _read(lock)
                raise OutputBusy(f"{what} {self.path} is being written by another vistrack run"
                                 f"{f' (process {holder})' if holder else ''}; wait for it or write elsewhere") \
                    from None
            # the holder before us may have removed the file after we opened it: lock the file the name holds
            if file_id(lock) == _fd_id(fd):
                break
            os.close(fd)
        else:  # pragma: no cover - a lock file replaced 20 times in a row
            raise OutputBusy(f"cannot lock {what} {self.path}")
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode())
        self._fd, self.lock = fd, lock

    def release(self):
        """Remove the lock file and release the lock (idempotent)."""
        if self._fd is None:
            return
        try:
            self.lock.unlink(missing_ok=True)
        finally:
            os.close(self._fd)
            self._fd = None


def _fd_id(fd):
    st = os.fstat(fd)
    return (st.st_dev, st.st_ino)


def _read(path):
    try:
        return Path(path).read_text().strip()
    except OSError:
        return ""
