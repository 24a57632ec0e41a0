"""The files a run writes frame by frame: the track CSV and the toolkits' result files
(:class:`TrackCSV`), whole or not at all (a temporary name of their own, renamed when the run ends).

A write that fails (a full disk) never costs an earlier file: the output is replaced only by a file
whose every row was written, flushed and closed (:mod:`vistrack.io.outputs`). Where no earlier file
is there, the rows written whole before the failure are kept (a shorter track, as after Ctrl-C).
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

from .clips import format_value
from .outputs import OutputError, OutputLock, check_not_input, left_note, output_target, temporary_name
from .results_format import format_line

__all__ = ["TrackCSV", "TRACK_COLUMNS", "LOST_REASONS", "column_name", "check_lost_reason", "columns_help"]

#: the track CSV's columns (a model writes those of its kind: its ``describe``), each with what it holds; ``qx0..``
#: stands for ``qx0, qx1, ...``. The one list that ``run --help`` gives and docs/tracking.md must.
TRACK_COLUMNS = {
    "frame": "the frame's index in the input, from 0",
    "visible": "1: the object reported at the estimate; 0: not (lost_reason)",
    "id": "several plates (--targets): the plate's id (-1: none)",
    "cx": "the estimate's centre x, 0-based pixels",
    "cy": "the estimate's centre y, 0-based pixels",
    "w": "the estimate's box width, pixels",
    "h": "the estimate's box height, pixels",
    "angle_deg": "its rotation, degrees",
    "scale": "its scale",
    "qx0..": "contour: the support points' x",
    "qy0..": "contour: the support points' y",
    "x0..": "plate: the vertices' x (x0..x3)",
    "y0..": "plate: the vertices' y (y0..y3)",
    "lx0..": "landmarks: the landmarks' x",
    "ly0..": "landmarks: the landmarks' y",
    "redetected": "box: 1 where a whole-frame search found it again",
    "ess": "the effective sample size of the frame's particles",
    "ms": "milliseconds the filter spent on the frame",
    "lost_reason": "empty where visible is 1, else why not (below)",
    "confidence": "box: the probability in [0, 1] that the box is on it",
}

#: every value the track CSV's ``lost_reason`` takes where ``visible`` is 0, and what it means (the models' own
#: verdicts, :data:`vistrack.models.collapse.REASONS`, then the frames the filter did not track)
LOST_REASONS = {
    "collapse": "its scale or the likelihood there collapsed",
    "low-confidence": "box: its calibrated confidence below the threshold",
    "out-of-frame": "the estimate's centre left the frame",
    "not found": "no plate passes the test, or none found yet",
    "decode": "the frame failed to decode",
    "not started": "before the first ground-truth box (--init-gt)",
}


def column_name(column):
    """The :data:`TRACK_COLUMNS` entry of a track CSV column: ``qx3`` -> ``qx0..``, ``cx`` -> ``cx``."""
    stem = column.rstrip("0123456789")
    return f"{stem}0.." if stem != column and f"{stem}0.." in TRACK_COLUMNS else column


def check_lost_reason(reason):
    """``reason`` when it is ``""`` or one of :data:`LOST_REASONS`; a ``ValueError`` otherwise (a model that
    writes a value nobody documented)."""
    if reason and reason not in LOST_REASONS:
        raise ValueError(f"lost_reason {reason!r} is not one of {', '.join(LOST_REASONS)} "
                         "(vistrack.io.track_files.LOST_REASONS)")
    return reason


def columns_help():
    """The track CSV's columns and ``lost_reason`` values as ``--help`` text (:data:`TRACK_COLUMNS`,
    :data:`LOST_REASONS`): two blocks of a line each that click keeps as they are."""
    cols = "\n".join(f"  {k:<12} {v}" for k, v in TRACK_COLUMNS.items())
    reasons = "\n".join(f"  {k:<15} {v}" for k, v in LOST_REASONS.items())
    return (f"\b\nTrack CSV columns (a model writes those of its kind):\n{cols}\n\n"
            f"\b\nlost_reason where visible=0:\n{reasons}")


class TrackCSV:
    """Track rows (dicts) written as they come: header from the first row, one flushed row per
    :meth:`write` to ``path.part``; :meth:`close` renames it to ``path`` (module docstring); a
    symbolic link is written through to its file, a device or pipe (``/dev/stdout``) in place
    (:func:`~vistrack.io.outputs.output_target`), and an input of the command is refused.
    ``boxes``: a result file of the tracking toolkits instead (:mod:`vistrack.io.results_format`):
    ``"otb"`` (or ``True``), ``"got10k"``, ``"vot"`` — ``x,y,w,h`` per frame, no header — or
    ``"time"``, GOT-10k's seconds per frame."""

    def __init__(self, path, boxes=False):
        self.path = Path(path)
        self.what = "track file" if not boxes else "results file"
        check_not_input(self.path, self.what)
        # a device or pipe (/dev/stdout) is written in place: a part file renamed over it would replace it;
        # a link is written through to its file, the link kept
        self.target, self.direct = output_target(self.path)
        # one live writer per output (a second run refuses it: OutputBusy), and a temporary name of its own
        self._lock = OutputLock(self.target, self.what)
        try:
            self.part = self.target if self.direct else temporary_name(self.target)
            self._f = open(self.part, "w", newline="")
        except BaseException:
            self._lock.release()
            raise
        self._w = csv.writer(self._f)
        self.boxes = "otb" if boxes is True else (boxes or None)
        self.columns = None
        self.rows = 0
        self._done = False
        self._error = None  # the write that failed
        self._complete = True  # False: the run failed (abandon)
        self._whole = 0  # bytes of the part file that hold whole rows

    def write(self, row):
        """Write one track ``row`` (a dict: column -> value; ``visible``, ``cx``, ``cy``, ``w``, ``h`` for the box
        format) and flush it. A failed write (``OSError``: a full disk) raises
        :class:`~vistrack.io.outputs.OutputError` naming :attr:`path`, and :meth:`close` then keeps
        the earlier file (module docstring)."""
        try:
            self._write(row)
        except Exception as e:
            self._error = self._error or e
            if isinstance(e, OSError) and not self.direct:
                raise OutputError(self.what, self.path, e, self._left()) from None
            raise
        self.rows += 1
        if not self.direct:
            self._whole = os.lseek(self._f.fileno(), 0, os.SEEK_CUR)

    def _left(self):
        """What a failure leaves at :attr:`path`: the earlier file, or the rows written whole."""
        if self.target.is_file():
            return left_note(self.path, True)
        return f"the {self.rows} rows written before are kept" if self.rows else left_note(self.path, False)

    def _write(self, row):
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

    def abandon(self):
        """The run writing this file failed: :meth:`close` keeps an earlier :attr:`path`."""
        self._complete = False

    def close(self):
        """Close and rename to :attr:`path` (a run without frames removes the part file). After a
        failed write or close (a full disk), or after :meth:`abandon` (the run failed), an
        earlier :attr:`path` is kept and the part file removed; with no earlier file the rows
        written whole so far are kept."""
        if self._done:
            return
        self._done = True
        raised = self._error is not None  # write() raised it
        try:
            self._f.close()
        except OSError as e:  # the last rows did not reach the disk
            self._error = self._error or e
        try:
            if self.direct:
                return
            if self._error is not None or not self._complete:
                left = self._left()
                self._keep_whole_rows()
                if self._error is not None and not raised:
                    raise OutputError(self.what, self.path, self._error, left)
            elif self.rows:
                os.replace(self.part, self.target)
        finally:
            if not self.direct:
                self.part.unlink(missing_ok=True)
            self._lock.release()

    def _keep_whole_rows(self):
        """After a failure: the part file cut to its whole rows and renamed to :attr:`path` when no
        earlier file is there and it holds rows; else removed."""
        if not self.target.is_file() and self.rows:
            try:
                os.truncate(self.part, self._whole)
                os.replace(self.part, self.target)
            except OSError:
                pass
        self.part.unlink(missing_ok=True)
