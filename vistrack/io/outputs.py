"""The output-path layer: every file a run writes goes through here.

* :func:`same_file`: two names of one file, by identity (``st_dev``, ``st_ino``), not by
  spelling: a hard link, a symbolic link or ``./x`` against ``x``.
* :func:`output_target`: where an output is written and how. A symbolic link is written through
  to the file it names (the link stays a link); a name that leads to a process's descriptor
  (``/dev/stdout``: ``/proc/self/fd/1``), a character device or a FIFO is written in place, never
  replaced by a rename.
* :func:`check_writable`: whether a file can be written at a path, before any work.
* :func:`input_files`: the files a run reads from a video, clip or image folder (what an output
  must never be); :func:`check_outputs`: a command's outputs checked against its inputs and each
  other before any work, the inputs then kept for the command (:func:`command_inputs`) so that
  every writer refuses them too (:func:`check_not_input`).
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

import contextvars
import errno
import os
from contextlib import contextmanager
from pathlib import Path

from .clip_files import CLIP_FILES, FRAME_FOLDERS, IMAGE_EXT

__all__ = ["OutputBusy", "OutputError", "OutputIsInput", "same_file", "file_id", "check_writable", "input_files",
           "OutputLock", "temporary_name", "output_target", "in_place", "replacing", "left_note", "command_inputs",
           "declare_inputs", "check_outputs", "check_not_input"]


class OutputBusy(RuntimeError):
    """Another live process writes this output."""


class OutputIsInput(ValueError):
    """An output names a file the command reads (one line: the output, the input, what to do)."""


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
    they are). The output's lock is held meanwhile (:class:`OutputBusy` when another process holds
    it); a symbolic link is written through to its file; a device or pipe (``/dev/stdout``) is
    yielded itself and written in place (:func:`output_target`); an input of the command is
    refused (:func:`check_not_input`)."""
    path = Path(path)
    check_not_input(path, what)
    target, direct = output_target(path)
    if direct:
        try:
            yield target
        except OutputError:
            raise
        except OSError as e:  # a device's own error (/dev/full: a full disk), naming the output
            raise OutputError(what, path, e) from None
        return
    lock = OutputLock(target, what)
    earlier = target.is_file()
    tmp = None
    try:
        tmp = temporary_name(target, tag)
        yield tmp
        os.replace(tmp, target)
    except OutputError:
        raise
    except OSError as e:
        raise OutputError(what, path, e, left_note(path, earlier)) from None
    finally:
        if tmp is not None:
            tmp.unlink(missing_ok=True)
        lock.release()


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
    if "://" in str(path):
        raise ValueError(f"{what} {path}: a URL; vistrack writes its outputs to local files: give a local path")
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


#: folders whose names stand for a process's open descriptors (``/dev/stdout`` leads there)
_DESCRIPTORS = ("/proc/", "/dev/fd/")


def output_target(path):
    """``(target, in_place)``: the file an output named ``path`` is written to, and whether it is
    written in place (opened and written) rather than replaced (a temporary file renamed over it).

    A symbolic link is followed to the file it names: the output is written there and the link stays
    a link (a rename over the link would replace it). A name that leads into ``/proc`` or
    ``/dev/fd`` (``/dev/stdout`` is a link to ``/proc/self/fd/1``: the process's standard output,
    a terminal, a pipe or the file a shell opened), a character device or a FIFO is written in place:
    a rename would replace the device node, and a shell's file would keep the old, unlinked copy."""
    p = os.path.abspath(path)
    for _ in range(40):
        if p.startswith(_DESCRIPTORS):
            return Path(p), True
        if not os.path.islink(p):
            break
        folder = os.path.realpath(os.path.dirname(p))
        p = os.path.normpath(os.path.join(folder, os.readlink(p)))
    else:
        raise OSError(errno.ELOOP, os.strerror(errno.ELOOP), str(path))
    return Path(p), os.path.exists(p) and not os.path.isfile(p) and not os.path.isdir(p)


def in_place(path):
    """Whether an output named ``path`` is written in place (a device, a pipe, ``/dev/stdout``:
    :func:`output_target`); such outputs may also be shared by several writers."""
    return output_target(path)[1]


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


#: what the command running in this context reads: ``{"files": {key: shown}, "folders": {real path: shown}}``
#: (keys: a file's identity and its real path); ``None`` outside :func:`command_inputs`
_READS = contextvars.ContextVar("vistrack_reads", default=None)


@contextmanager
def command_inputs():
    """The scope of one command (the command line opens one per command): the inputs declared in it
    (:func:`check_outputs`, :func:`declare_inputs`) are refused as outputs by every writer in it
    (:func:`check_not_input`)."""
    token = _READS.set({"files": {}, "folders": {}})
    try:
        yield
    finally:
        _READS.reset(token)


def declare_inputs(paths):
    """Declare ``paths`` read by the command (files, or folders: a clip, an image folder, a folder of
    clips); nothing outside :func:`command_inputs`. A URL or a path that is not there is skipped."""
    reads = _READS.get()
    if reads is None:
        return
    for p in paths:
        if p is None or "://" in str(p) or not os.path.exists(p):
            continue
        if os.path.isdir(p):
            reads["folders"][os.path.realpath(p)] = str(p)
            files = input_files(p)
        else:
            files = [Path(p)]
        for f in files:
            reads["files"][os.path.realpath(f)] = str(f)
            reads["files"][file_id(f)] = str(f)


def _read_by(real):
    """The input a file at real path ``real`` would overwrite (a declared file by identity or path,
    or a clip's own file inside a declared folder: its ground truth, meta.json, video or frames,
    also one level down in a folder of clips), or ``None``."""
    reads = _READS.get()
    if not reads:
        return None
    hit = reads["files"].get(file_id(real)) or reads["files"].get(real)
    if hit:
        return hit
    for folder, shown in reads["folders"].items():
        rel = os.path.relpath(real, folder)
        parts = rel.split(os.sep)
        if rel.startswith(os.pardir) or len(parts) > 3:
            continue
        name = parts[-1]
        if name in CLIP_FILES or os.path.splitext(name)[1].lower() in IMAGE_EXT or \
                (len(parts) > 1 and parts[-2] in FRAME_FOLDERS):
            return os.path.join(shown, rel)
    return None


def check_not_input(path, what="output"):
    """Raise :class:`OutputIsInput` (one line) when ``path`` names a file the command reads (declared in
    its :func:`command_inputs` scope): the same file by identity or real path, through any link."""
    target, direct = output_target(path)
    if direct:
        return
    hit = _read_by(os.path.realpath(target))
    if hit:
        same = os.path.realpath(target) == os.path.realpath(hit) and Path(path).name == Path(hit).name
        which = Path(hit).name if same else f"{hit}, the same file under another name"
        raise OutputIsInput(f"{what} {path} would overwrite the input it reads ({which}); write elsewhere")


def check_outputs(outputs, inputs=()):
    """Before any work: raise ``ValueError`` (one line) when two of ``outputs`` (``{name: path or
    None}``, ``name`` the option; a file, or a folder the command writes into) are one file, one would
    overwrite one of ``inputs`` (files and folders the command reads: :func:`check_not_input`) or a
    folder output is a folder of ``inputs``; then ``inputs`` stay declared for the command
    (:func:`declare_inputs`), so that every writer refuses them. Devices and pipes may be shared."""
    scoped = _READS.get() is not None
    token = None if scoped else _READS.set({"files": {}, "folders": {}})
    try:
        declare_inputs(inputs)
        seen = {}
        for name, path in outputs.items():
            if path is None or "://" in str(path):
                continue
            target, direct = output_target(path)
            if direct:
                continue
            folder = _READS.get()["folders"].get(os.path.realpath(target))
            if folder is not None:
                raise ValueError(f"{name} {path} is the folder {folder} that the command reads: its files would be "
                                 "mixed with the outputs; write elsewhere")
            key = file_id(target) or os.path.realpath(target)
            if key in seen:
                raise ValueError(f"{seen[key]} and {name} name the same file {path}")
            seen[key] = name
            check_not_input(path, name)
    finally:
        if token is not None:
            _READS.reset(token)


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
        target, direct = output_target(self.path)
        if direct:
            return
        import fcntl

        lock = target.with_name(f".{target.name}.lock")  # every name of one file takes the same lock
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
