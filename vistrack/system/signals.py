"""Signals during a run: Ctrl-C and SIGTERM stop it after the frame in hand, every output flushed
(:func:`deferred_signals`); the exception a SIGTERM raises (:class:`Terminated`); and Ctrl-C while
nothing is open (a command's start-up and shut-down: :func:`interrupt_aborts`), which ends the
process at once with ``Aborted.`` and exit code 130. SIGHUP (a closed terminal, a dropped ssh
session) is handled as SIGTERM is (:data:`TERMINATING`): what was done is kept; a SIGHUP the process
ignores (``nohup``) stays ignored."""

from __future__ import annotations

import signal
from contextlib import contextmanager

__all__ = ["Terminated", "TERMINATING", "stop_on_signals", "deferred_signals", "stop_reason", "HARD_STOP",
           "interrupt_aborts", "abort_on_interrupt"]


class Terminated(KeyboardInterrupt):
    """SIGTERM (or SIGHUP), raised where the run is, so that it ends as cleanly as on Ctrl-C."""


#: the signals that end a run as SIGTERM does: SIGTERM, and SIGHUP where the platform has it
TERMINATING = tuple(s for s in (signal.SIGTERM, signal.Signals.__members__.get("SIGHUP")) if s is not None)


@contextmanager
def stop_on_signals():
    """Within the block SIGTERM and SIGHUP (:data:`TERMINATING`) raise :class:`Terminated` (SIGINT
    already raises ``KeyboardInterrupt``); an ignored one stays ignored; the previous handlers are
    restored after."""
    def handler(signum, frame):
        raise Terminated()

    try:
        old = {s: signal.getsignal(s) for s in TERMINATING}
        for s, h in old.items():
            if h is not signal.SIG_IGN:
                signal.signal(s, handler)
    except ValueError:  # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        for s, h in old.items():
            if h is not signal.SIG_IGN and h is not None:
                signal.signal(s, h)


class _Stop:
    """What :func:`deferred_signals` caught: ``reason`` (``None``, ``"interrupt"`` or
    ``"terminate"``) and how many signals."""

    def __init__(self):
        self.reason, self.count = None, 0


#: signals after which a run stops at once (raises) instead of after the frame in hand
HARD_STOP = 3


@contextmanager
def deferred_signals():
    """Within the block SIGINT, SIGTERM and SIGHUP set a flag (the yielded object's ``reason``:
    ``"terminate"`` once a SIGTERM or SIGHUP came, else ``"interrupt"``) instead of raising, so the
    frame in hand is finished and every writer flushed before the run stops; the
    :data:`HARD_STOP`-th signal raises (``KeyboardInterrupt``, or :class:`Terminated` for SIGTERM and
    SIGHUP) for a run that does not come back. A signal the process ignores (a background job's
    SIGINT, ``nohup``'s SIGHUP) stays ignored. Outside the main thread signals are left alone."""
    import threading

    stop = _Stop()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def handler(signum, frame):
        stop.count += 1
        if stop.reason is None or signum in TERMINATING:  # a SIGTERM (shutdown) outranks Ctrl-C
            stop.reason = "terminate" if signum in TERMINATING else "interrupt"
        if stop.count >= HARD_STOP:
            raise Terminated() if signum in TERMINATING else KeyboardInterrupt()

    old = {s: signal.getsignal(s) for s in (signal.SIGINT, *TERMINATING)}
    for s, h in old.items():
        if h is not signal.SIG_IGN:
            signal.signal(s, handler)
    try:
        yield stop
    finally:
        for s, h in old.items():
            if h is not signal.SIG_IGN and h is not None:
                signal.signal(s, h)


def stop_reason(exc):
    """``"terminate"`` (SIGTERM) or ``"interrupt"`` (Ctrl-C) for the exception that stopped a run;
    re-raises any other. A signal that arrives while a compiled kernel is being called surfaces as
    a ``SystemError`` caused by the handler's exception (numba's dispatcher returns with it set)."""
    cause = exc.__cause__ if isinstance(exc, SystemError) else exc
    if not isinstance(cause, KeyboardInterrupt):
        raise exc
    return "terminate" if isinstance(cause, Terminated) else "interrupt"


def _abort(signum, frame):
    import os

    os.write(2, b"Aborted.\n")
    os._exit(130)


def abort_on_interrupt():
    """From now on Ctrl-C ends the process at once with ``Aborted.`` and exit code 130, no
    traceback (a command line whose work is done and whose files are closed: its shut-down). A
    SIGINT the process ignores stays ignored; outside the main thread nothing changes. Returns the
    handler it replaced (``None`` where it changed nothing)."""
    try:
        old = signal.getsignal(signal.SIGINT)
        if old is signal.SIG_IGN:
            return None
        signal.signal(signal.SIGINT, _abort)
    except ValueError:  # not the main thread
        return None
    return old


@contextmanager
def interrupt_aborts():
    """Within the block Ctrl-C ends the process at once with ``Aborted.`` and exit code 130
    (:func:`abort_on_interrupt`): for the seconds a command line spends loading its modules, when
    nothing is open yet. The previous handler is restored after."""
    old = abort_on_interrupt()
    try:
        yield
    finally:
        if old is not None:
            signal.signal(signal.SIGINT, old)
