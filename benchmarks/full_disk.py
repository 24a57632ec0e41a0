"""vistrack on a full disk: commands run over a small tmpfs, and what they leave there.

    python benchmarks/full_disk.py '{"size": "48k", "steps": [["run", "v.avi", "--out", "{T}/a.mp4"]]}'

:func:`on_tmpfs` mounts a tmpfs of ``size`` in a private mount namespace (``unshare -m`` as root,
``unshare -rm`` otherwise: nothing outlives the process, nothing else sees it), runs each step there
(``python -m vistrack.cli ARGV``, ``{T}`` standing for the tmpfs folder) and records after each its
exit code, its stderr and every file in the folder and below (hidden ones too: a temporary file
left behind shows), by its path there: size, SHA-256 and, for a video, the frames OpenCV decodes
(-1: it does not open). Where no tmpfs can be mounted (no ``unshare``, no privilege) it raises
:class:`Unavailable` with the reason: the tests skip, ``soak.py`` says so.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

__all__ = ["Unavailable", "on_tmpfs"]

VIDEOS = (".mp4", ".avi", ".mkv", ".mov", ".m4v")


class Unavailable(RuntimeError):
    """No small tmpfs can be mounted here."""


def on_tmpfs(steps, size="48k", cwd=None, timeout=300):
    """Run ``steps`` (vistrack argument lists; ``{T}`` is the tmpfs folder) on a tmpfs of ``size``.

    Returns ``[{"code", "err", "files": {name: {"size", "sha256", "frames"}}}]``, one per step.
    Raises :class:`Unavailable` where no tmpfs can be mounted."""
    unshare = shutil.which("unshare")
    if unshare is None:
        raise Unavailable("no unshare command to mount a tmpfs in a private namespace")
    spec = json.dumps({"size": size, "steps": steps})
    cmd = [unshare, "-m" if os.geteuid() == 0 else "-rm", sys.executable, __file__, spec]
    p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    if p.returncode == 77 or (p.returncode and not p.stdout.strip()):
        raise Unavailable(f"cannot mount a {size} tmpfs here: {(p.stderr.strip() or p.stdout.strip())[-200:]}")
    return json.loads(p.stdout)


def _files(folder):
    import cv2

    out = {}
    for p in sorted(q for q in Path(folder).rglob("*") if q.is_file()):
        data = p.read_bytes()
        frames = None
        if p.suffix.lower() in VIDEOS:
            cap = cv2.VideoCapture(str(p))
            frames = -1 if not cap.isOpened() else 0
            while frames >= 0 and cap.read()[0]:
                frames += 1
            cap.release()
        out[str(p.relative_to(folder))] = {"size": len(data), "sha256": hashlib.sha256(data).hexdigest(),
                                           "frames": frames}
    return out


def _main(spec):
    """In the private namespace: mount, run the steps, print the record as JSON."""
    spec = json.loads(spec)
    folder = Path(tempfile.mkdtemp(prefix="vistrack-full-"))
    m = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={spec['size']}", "tmpfs", str(folder)],
                       capture_output=True, text=True)
    if m.returncode:
        print(m.stderr.strip() or "mount failed", file=sys.stderr)
        sys.exit(77)
    env = {**os.environ, "OPENCV_FFMPEG_LOGLEVEL": "-8", "OPENCV_LOG_LEVEL": "ERROR"}
    record = []
    try:
        for argv in spec["steps"]:
            argv = [a.replace("{T}", str(folder)) for a in argv]
            p = subprocess.run([sys.executable, "-m", "vistrack.cli", *argv], capture_output=True, text=True,
                               env=env)
            record.append({"code": p.returncode, "err": p.stderr.replace(str(folder), "{T}"),
                           "files": _files(folder)})
    finally:
        subprocess.run(["umount", str(folder)], capture_output=True)
        folder.rmdir()
    print(json.dumps(record))


if __name__ == "__main__":
    _main(sys.argv[1])
