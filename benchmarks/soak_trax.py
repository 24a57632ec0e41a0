"""The soak's TraX and start-up scenarios (:mod:`soak`), and the pieces the tests share with them
(:data:`INTERRUPT_AT`, :func:`trax_session`): ``vistrack trax`` with bad options, no client, a broken or
dead one, session errors; Ctrl-C while a command starts, waits or ends. What they may break: a hang, a
traceback, a client never told why."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import soak_harness as S

#: Ctrl-C at a chosen moment of a command line's life: its start-up (while its modules load) or
#: its shut-down (its command done). ``python -c INTERRUPT_AT WHERE ARGV...``
INTERRUPT_AT = """
import os, signal, sys, atexit
signal.signal(signal.SIGINT, signal.default_int_handler)
where = sys.argv.pop(1)
if where == "start-up":  # Ctrl-C while the command line loads its modules
    class Hook:
        def find_spec(self, name, path=None, target=None):
            if name == "vistrack.cli.demo":
                os.kill(os.getpid(), signal.SIGINT)
            return None
    sys.meta_path.insert(0, Hook())
elif where == "shut-down":  # Ctrl-C once the command is done, while the process ends
    atexit.register(lambda: os.kill(os.getpid(), signal.SIGINT))
from vistrack.cli import main
main()
"""


def trax_session(first, box, second=None, argv=("trax",), timeout=120):
    """Drive ``vistrack trax`` with vot-trax's own client: initialise on image ``first`` at ``box``,
    then send ``second`` (if given). Returns ``(returncode, stderr, what the client heard)``: the
    boxes, or the session's end reason."""
    import trax
    from trax.client import Client
    from trax.image import FileImage
    from trax.region import Rectangle

    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", *argv], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        client = Client((proc.stdin.fileno(), proc.stdout.fileno()), timeout=timeout, log=[].append)
        try:
            objs, _ = client.initialize({"color": FileImage.create(str(first))}, [(Rectangle.create(*box), {})], {})
            heard = [objs[0][0].bounds()]
            if second is not None:
                objs, _ = client.frame({"color": FileImage.create(str(second))}, {}, [])
                heard.append(objs[0][0].bounds())
            client.quit()
        except trax.TraxException as e:
            heard = str(e)
    finally:
        proc.stdin.close()
        err = proc.stderr.read()
        proc.wait(timeout=timeout)
    return proc.returncode, err, heard


def scenarios():
    """The TraX and start-up scenarios."""
    return _trax_and_signals() + _dead_clients()


def _trax(case):
    """A driver: a TraX session whose ``case`` ("outside", "missing", "size") fails; the client
    must hear why (else silent wrong)."""

    def driver(w, argv, timeout):
        import cv2

        try:
            import trax  # noqa: F401
        except ImportError:
            return S.Result(None, "", "", 0.0, skip="vot-trax is not installed")
        frames = [f for f in S._frames(2)]
        cv2.imwrite(str(w / "f0.png"), frames[0])
        cv2.imwrite(str(w / "f1.png"), frames[1][: S.H // 2])
        box = (1000, 1000, 20, 20) if case == "outside" else tuple(float(v) for v in S.INIT.split(","))
        second = {"outside": None, "missing": w / "nothere.png", "size": w / "f1.png"}[case]
        t0 = time.time()
        code, err, heard = trax_session(w / "f0.png", box, second, timeout=timeout)
        res = S.Result(code, "", err, time.time() - t0)
        if not isinstance(heard, str) or "terminated the session" not in heard:
            res.code, res.note = 0, f"the client heard {heard!r}, not why the session failed"
        return res

    return driver


def _interrupt_at(where):
    def driver(w, argv, timeout):
        t0 = time.time()
        p = subprocess.run([sys.executable, "-c", INTERRUPT_AT, where, *argv], cwd=w, capture_output=True, text=True,
                           timeout=timeout)
        return S.Result(p.returncode, p.stdout, p.stderr, time.time() - t0)

    return driver


def _aborted(w, res):
    if res.code != 130 or res.err.strip() != "Aborted.":
        return "misleading error", f"exit {res.code}, stderr {res.err.strip()[-80:]!r} (expected Aborted., 130)"
    return None


def _no_hello(w, res):
    return ("misleading error", "the hello went out before the options were checked") if res.out else None


def _trax_and_signals():
    return [
        S.Scenario("trax --model nonsense", ["trax", "--model", "nonsense"], mention="nonsense", check=_no_hello,
                   driver=S.stdin("")),
        S.Scenario("trax --algo pf-eis", ["trax", "--algo", "pf-eis"], mention="pf-eis", check=_no_hello,
                   driver=S.stdin("")),
        S.Scenario("trax -n 0", ["trax", "-n", "0"], mention="particles", check=_no_hello, driver=S.stdin("")),
        S.Scenario("trax, nothing on stdin", ["trax"], mention="TraX client", driver=S.stdin("")),
        S.Scenario("trax, garbage on stdin", ["trax"], mention="TraX client", driver=S.stdin("garbage\n" * 3)),
        *[S.Scenario(f"trax session error: {case}", ["trax"], mention=m, driver=_trax(case))
          for case, m in (("outside", "outside"), ("missing", "nothere.png"), ("size", "started on"))],
        S.Scenario("Ctrl-C while the command line loads", ["--version"], "ok", codes=(130,), check=_aborted,
                   driver=_interrupt_at("start-up")),
        S.Scenario("Ctrl-C while the process ends", ["--version"], "ok", codes=(130,), check=_aborted,
                   driver=_interrupt_at("shut-down")),
        S.Scenario("Ctrl-C while trax waits for its client", ["trax"], "ok", codes=(130,), check=_aborted,
                   driver=_trax_waiting()),
        S.Scenario("Ctrl-C 0.3 s into eval", S.EV("{fx}/suite"), "ok", codes=(130,), check=_aborted,
                   driver=S.signals([signal.SIGINT], S.after(0.3))),
    ]


def _trax_waiting():
    """A driver: Ctrl-C once ``vistrack trax`` said hello and waits for its client."""

    def driver(w, argv, timeout):
        t0 = time.time()
        p = subprocess.Popen([sys.executable, "-m", "vistrack.cli", *argv], cwd=w, stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        hello = p.stdout.readline()
        p.send_signal(signal.SIGINT)
        res = S._finish(p, t0, timeout)
        if not hello.startswith("@@TRAX:hello"):
            res.note = f"no hello before the signal: {hello[:40]!r}"
        return res

    return driver


def _frame(w):
    import cv2

    cv2.imwrite(str(w / "f.png"), next(S._frames(1)))


def _session(w, region, second=None):
    """A raw TraX v4 session's text: initialise ``region`` on ``w/f.png``, then ``second`` (a frame path)."""
    text = f'@@TRAX:initialize "{region}"\n@@TRAX:frame "file://{w}/f.png"\n'
    return text + (f'@@TRAX:frame "{second}"\n' if second else "")


def _raw(region, second=None):
    """A driver: a raw TraX session (:func:`_session`) on standard input."""

    def driver(w, argv, timeout):
        _frame(w)
        return S.stdin(_session(w, region, second))(w, argv, timeout)

    return driver


def _silent_client(w, argv, timeout):
    """A driver: a client that initialises, then says nothing (but lives); SIGTERM once it waits."""
    t0 = time.time()
    p = subprocess.Popen([sys.executable, "-m", "vistrack.cli", *argv], cwd=w, stdin=subprocess.PIPE,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    p.stdout.readline()
    p.stdin.write('@@TRAX:initialize "41,48,25,19" \n')
    p.stdin.flush()
    p.terminate()
    return S._finish(p, t0, timeout)


def _non_ascii_session(w, argv, timeout):
    """A driver: vot-trax's own client with the frames under a non-ASCII folder."""
    try:
        import trax  # noqa: F401
    except ImportError:
        return S.Result(None, "", "", 0.0, skip="vot-trax is not installed")
    (w / "ünï").mkdir()
    _frame(w / "ünï")
    t0 = time.time()
    code, err, heard = trax_session(w / "ünï" / "f.png", (40.0, 40.0, 25.0, 25.0), w / "ünï" / "f.png",
                                    timeout=timeout)
    res = S.Result(code, "", err, time.time() - t0)
    if code == 0 and not isinstance(heard, list):
        res.code, res.note = 1, f"the client heard {heard!r}"
    return res


def _terminated(w, res):
    return None if res.code == 143 and res.err.strip() == "Terminated." else \
        ("misleading error", f"exit {res.code}, stderr {res.err.strip()[-60:]!r} (expected Terminated., 143)")


def _dead_clients():
    """Issue 55's TraX cases: a client that dies mid-session or cuts a message short, a bad TRAX_SOCKET, a
    region that is not a box, a silent client and SIGTERM, non-ASCII paths, frames that are not image files."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        closed = str(s.getsockname()[1])  # nothing listens there once the socket is closed
    return [
        S.Scenario("trax, the client dies after its first message", ["trax"], mention="went away",
                   driver=S.stdin('@@TRAX:initialize "41,48,25,19" \n')),
        S.Scenario("trax, a message cut short", ["trax"], mention="TraX client",
                   driver=S.stdin('@@TRAX:initialize "41,48,25,1')),
        S.Scenario("trax, TRAX_SOCKET=garbage", ["trax"], mention="TRAX_SOCKET", check=_no_hello,
                   driver=S.stdin("", env={"TRAX_SOCKET": "garbage"})),
        S.Scenario("trax, TRAX_SOCKET where nothing listens", ["trax"], mention="no TraX client answers",
                   check=_no_hello, driver=S.stdin("", env={"TRAX_SOCKET": closed})),
        *[S.Scenario(f"trax, start region {name}", ["trax"], mention="start region", driver=_raw(region))
          for name, region in (("abc", "abc"), ("NaN", "nan,nan,nan,nan"), ("1e999", "1e999,3,4,5"),
                               ("of a million digits", "9" * 1000000 + ",1,2,3"))],
        S.Scenario("trax, a silent client and SIGTERM", ["trax"], "ok", codes=(143,), check=_terminated,
                   driver=_silent_client),
        S.Scenario("trax, frames under a non-ASCII folder", ["trax"], "ok", driver=_non_ascii_session),
        S.Scenario("trax, a frame that is a folder", ["trax"], mention="a folder",
                   driver=_raw("30,30,25,25", "file://{w}")),
        S.Scenario("trax, a frame given as an http:// address", ["trax"], mention="http://",
                   driver=_raw("30,30,25,25", "http://127.0.0.1:9/f.png")),
    ]
