"""Result files of the tracking toolkits: what ``run --results`` writes and ``eval --results-dir`` reads.

========  ===========================================  =======  ==========================================
format    layout                                       origin   lines
========  ===========================================  =======  ==========================================
otb       ``FILE`` (``DIR/<sequence>.txt`` for eval)   1-based  ``x,y,w,h`` per frame, ``0,0,0,0`` where
                                                                the object is not reported (the OTB toolkit
                                                                and pytracking write OTB results 1-based)
got10k    ``DIR/<seq>/<seq>_001.txt`` and              0-based  ``x,y,w,h`` per frame; ``_time.txt``: the
          ``DIR/<seq>/<seq>_time.txt``                          seconds each frame took
vot       ``DIR/<seq>/<seq>_001.txt``                  0-based  ``1`` on the first frame (initialised),
                                                                then ``x,y,w,h`` per frame (``0`` where the
                                                                object is not reported)
========  ===========================================  =======  ==========================================
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .numbers import parse_float

__all__ = ["FORMATS", "ORIGIN", "result_paths", "format_line", "find_result_file", "read_result_file"]

FORMATS = ("otb", "got10k", "vot")
#: pixel origin of each format's boxes
ORIGIN = {"otb": 1, "got10k": 0, "vot": 0}


def result_paths(path, fmt, sequence):
    """``(boxes file, time file or None)`` that ``run --results PATH --results-format FMT`` writes for
    ``sequence``: ``PATH`` itself for OTB; for GOT-10k and VOT, ``PATH`` is the results folder."""
    if fmt == "otb":
        return Path(path), None
    folder = Path(path) / sequence
    return folder / f"{sequence}_001.txt", (folder / f"{sequence}_time.txt" if fmt == "got10k" else None)


def format_line(box, visible, fmt, index=None):
    """One line of a result file for ``box`` ``(x, y, w, h)`` 0-based (``visible`` false: not reported)."""
    if fmt == "vot" and index == 0:
        return "1"
    if not visible:
        return "0" if fmt == "vot" else "0.00,0.00,0.00,0.00"
    x, y, w, h = (float(v) for v in box)
    o = ORIGIN[fmt]
    return f"{x + o:.2f},{y + o:.2f},{w:.2f},{h:.2f}"


def find_result_file(folder, sequence, fmt):
    """The result file of ``sequence`` in a results ``folder`` of format ``fmt`` (file names compared
    without case), or ``None``."""
    folder = Path(folder)
    if fmt == "otb":
        files = {p.name.lower(): p for p in folder.iterdir() if p.suffix.lower() == ".txt"}
        return files.get(f"{sequence}.txt".lower())
    subs = {p.name.lower(): p for p in folder.iterdir() if p.is_dir()}
    sub = subs.get(sequence.lower())
    if sub is None:
        return None
    files = {p.name.lower(): p for p in sub.iterdir() if p.is_file()}
    return files.get(f"{sequence}_001.txt".lower())


def read_result_file(path, fmt):
    """Boxes ``(T, 4)`` 0-based ``x, y, w, h`` from a result file, NaN where nothing is reported (VOT's
    ``0``/``2`` codes, ``0,0,0,0``) and on VOT's ``1`` initialisation lines (the caller knows that
    frame's box). A bad line is a ``ValueError`` naming the file and line."""
    rows = []
    with open(path, errors="replace") as f:
        for k, line in enumerate(f, 1):
            parts = line.replace(",", " ").replace("\t", " ").split()
            if not parts:
                continue
            try:
                v = np.array([parse_float(p) for p in parts])
            except ValueError:
                raise ValueError(f"{path}, line {k}: expected numbers, got {line.strip()[:60]!r}") from None
            if len(v) == 1 and fmt == "vot":
                rows.append(np.full(4, np.nan))
                continue
            if len(v) == 8:  # a polygon: its bounding box
                v = np.array([v[0::2].min(), v[1::2].min(), np.ptp(v[0::2]), np.ptp(v[1::2])])
            if len(v) != 4:
                raise ValueError(f"{path}, line {k}: expected x,y,w,h ({fmt} format), got {len(v)} values")
            if not (np.all(np.isfinite(v)) and v[2] > 0 and v[3] > 0):
                v = np.full(4, np.nan)
            else:
                v[:2] -= ORIGIN[fmt]
            rows.append(v)
    return np.array(rows, float).reshape(-1, 4)
