"""``vistrack run``: one video tracked, with its track file, annotated video and summary.

Public surface: :func:`prepare` (a :class:`Plan`: the model and algorithm chosen, the options checked, the
plate searched for), :func:`execute` (the plan tracked: a :class:`SessionLog`), :func:`record_video` (frames
tracked into the track CSV and the annotated video) and :func:`summary_lines` (what ``run`` prints after).
"""

from .plan import Plan, execute, prepare
from .recording import SessionLog, record_video
from .run_summary import summary_lines

__all__ = ["Plan", "prepare", "execute", "record_video", "SessionLog", "summary_lines"]
