"""The frame loop: one filter step per frame (:class:`Stepper`), and the timing of its stages.

Public surface: :class:`Stepper` (:meth:`~Stepper.step` one frame, :meth:`~Stepper.steps` over frames),
:class:`FrameResult` (the filter's state after a frame), :func:`warm_up` (the kernels loaded before the clock
starts), :func:`filter_ms` (a filter's time per frame, for equal-time comparisons), :class:`Timer`,
:data:`STAGES` and :func:`instrument` (time per stage).
"""

from .profiling import STAGES, Timer, instrument
from .stepper import FrameResult, Stepper, filter_ms, warm_up

__all__ = ["Stepper", "FrameResult", "warm_up", "filter_ms", "Timer", "STAGES", "instrument"]
