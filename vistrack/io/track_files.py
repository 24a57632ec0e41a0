"""The files a run writes frame by frame: the track CSV and the toolkits' result files
(:class:`TrackCSV`), whole or not at all (a temporary name of their own, renamed when the run ends)."""

from __future__ import annotations

import csv
import os
from pathlib import Path

from .clips import format_value
from .outputs import OutputLock, is_device, temporary_name
from .results_format import format_line

__all__ = ["TrackCSV"]


class TrackCSV:
    """Track rows (dicts) written as they come: header from the first row, one flushed row per
    :meth:`write` to ``path.part``; :meth:`close` renames it to ``path`` (module docstring); a
    device or pipe (``/dev/stdout``) is written directly.
    ``boxes``: a result file of the tracking toolkits instead (:mod:`vistrack.io.results_format`):
    ``"otb"`` (or ``True``), ``"got10k"``, ``"vot"`` — ``x,y,w,h`` per frame, no header — or
    ``"time"``, GOT-10k's seconds per frame."""

    def __init__(self, path, boxes=False):
        self.path = Path(path)
        # a device or pipe (/dev/stdout) is written directly: a part file renamed over it would replace it
        self.direct = is_device(self.path)
        # one live writer per output (a second run refuses it: OutputBusy), and a temporary name of its own
        self._lock = OutputLock(self.path, "results file" if boxes else "track file")
        try:
            self.part = self.path if self.direct else temporary_name(self.path)
            self._f = open(self.part, "w", newline="")
        except BaseException:
            self._lock.release()
            raise
        self._w = csv.writer(self._f)
        self.boxes = "otb" if boxes is True else (boxes or None)
        self.columns = None
        self.rows = 0
        self._done = False

    def write(self, row):
        """Write one track ``row`` (a dict: column -> value; ``visible``, ``cx``, ``cy``, ``w``, ``h`` for the box
        format) and flush it."""
        if self.boxes == "time":
            self._f.write(f"{float(row.get('ms') or 0.0) / 1e3:.6f}\n")
        elif self.boxes:
            box = (row["cx"] - row["w"] / 2, row["cy"] - row["h"] / 2, row["w"], row["h"])
            self._f.write(format_line(box, bool(row["visible"]), self.boxes, self.rows) + "\n")
        else:
            if self.columns is None:
                self.columns = list(row)
                self._w.writerow(self.columns)
            self._w.writerow([format_value(row.get(c, "")) for c in self.columns])
        self._f.flush()
        self.rows += 1

    def close(self):
        """Close and rename to :attr:`path` (a run without frames removes the part file); after a
        write error (disk full) the rows written whole so far are kept."""
        if self._done:
            return
        self._done = True
        try:
            self._f.close()
        except OSError:
            pass
        try:
            if self.direct:
                return
            if self.rows:
                os.replace(self.part, self.path)
            else:
                self.part.unlink(missing_ok=True)
        finally:
            self._lock.release()
