"""Issue 47's cases for ``soak.py`` (the third sweep), numbered by the issue's "What to build" items:
a full disk on a small tmpfs (1), sizes (2), the Python API (3), TraX and Ctrl-C at start-up and
shut-down (4), cached URL clips (5, issue 46's), run's summary against eval's (6), the minor and
wording cases (7). :func:`scenarios` takes the ``soak`` module (its ``Scenario``, helpers and fixtures).

The full-disk cases run where a tmpfs can be mounted in a private namespace
(:mod:`full_disk`); elsewhere they are ``skipped`` with the reason. The cases whose fix is issue
46's (URL cache validation, ``run 0`` beside a file ``0``, an unreachable URL's wording) count as
every other case: issue 46 has landed.
"""

from __future__ import annotations

import functools
import http.server
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time

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

#: a Python-API case: ``frames`` (5 BGR frames of a moving red box) and ``track(frames, **kw)`` (its
#: boxes from (30, 30, 25, 25)); the body's ValueError is one ``Error:`` line and exit 1; a silent
#: wrong result prints ``SILENT WRONG``.
API = """
import sys
import cv2
import numpy as np
import vistrack

def make_frames(n=5):
    out = []
    for k in range(n):
        f = np.full((90, 120, 3), 50, np.uint8)
        f[::6] = 80
        cv2.rectangle(f, (30 + 2 * k, 30), (54 + 2 * k, 54), (40, 60, 230), -1)
        out.append(f)
    return out

def track(frames, **kw):
    t = vistrack.Tracker(seed=3, particles=50, **kw)
    t.init(frames[0], (30, 30, 25, 25))
    return [t.box_estimate] + [t.update(f) and t.box_estimate for f in frames[1:]]

frames = make_frames()
try:
{body}
except ValueError as e:
    print(f"Error: {{e}}", file=sys.stderr)
    sys.exit(1)
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


def scenarios(S):
    """Issue 47's scenarios, built from the ``soak`` module ``S``."""
    return (_full_disk(S) + _sizes(S) + _api(S) + _trax_and_signals(S) + _urls(S) + _summary(S) + _minor(S))


# ---------------------------------------------------------------- 1: a full disk (small tmpfs)


def _tmpfs(S, steps, size="48k"):
    """A driver: the steps (vistrack argument lists; ``{T}`` the tmpfs) on a tmpfs; the result is
    the last step's, with the record of every step (``res.steps``)."""

    def driver(w, argv, timeout):
        from full_disk import Unavailable, on_tmpfs

        t0 = time.time()
        runs = [[a.format(w=w, fx=S.FX, T="{T}") for a in step] for step in steps]
        try:
            record = on_tmpfs(runs, size=size, cwd=w, timeout=timeout)
        except Unavailable as e:
            return S.Result(None, "", "", time.time() - t0, skip=str(e))
        except subprocess.TimeoutExpired:
            return S.Result(None, "", "", time.time() - t0, timeout=True)
        last = record[-1]
        res = S.Result(last["code"], "", last["err"], time.time() - t0)
        res.steps = record
        return res

    return driver


def _earlier_kept(name):
    """The first step wrote ``name``; after the failing last step it is there byte for byte, nothing
    else is left on the tmpfs, and the error names ``{T}/name``."""

    def check(w, res):
        first, last = res.steps[0], res.steps[-1]
        if first["code"] != 0 or name not in first["files"]:
            return "harness error", f"the earlier {name} was not written: {first['err'][-80:]}"
        if last["files"] != first["files"]:
            return "data loss", f"the tmpfs holds {sorted(last['files'])}, changed from {sorted(first['files'])}"
        if f"{{T}}/{name}" not in last["err"]:
            return "misleading error", f"the error does not name {name}: {last['err'][-100:]!r}"
        res.note = f"earlier {name} kept"
        return None

    return check


def _nothing_left(names):
    """No earlier file: after the failing step the tmpfs holds only ``names`` (whole files)."""

    def check(w, res):
        files = res.steps[-1]["files"]
        if sorted(files) != sorted(names):
            return "silent wrong", f"the tmpfs holds {sorted(files)} (expected {sorted(names)})"
        broken = [n for n, f in files.items() if f["frames"] is not None and f["frames"] <= 0]
        if broken:
            return "silent wrong", f"{broken[0]} does not play"
        return None

    return check


def _full_disk(S):
    long, short = "{fx}/long.avi", "{fx}/v.avi"
    run = ["run", "--init", S.INIT, "-n", "20", "-q"]
    out = []
    for name, size in (("old.mp4", "48k"), ("old.avi", "256k"), ("old.mkv", "48k")):  # Motion JPEG is larger
        steps = [[*run[:1], video, *run[1:], "--out", "{T}/" + name] for video in (short, long)]
        out.append(S.Scenario(f"#47-1 run --out over an earlier {name} on a full tmpfs", _shown(steps),
                              mention="No space left", driver=_tmpfs(S, steps, size), check=_earlier_kept(name)))
    for name in ("a.mp4", "a.avi"):
        steps = [[*run[:1], long, *run[1:], "--out", "{T}/" + name]]
        out.append(S.Scenario(f"#47-1 run --out {name} on a full tmpfs, no earlier file", _shown(steps),
                              mention=f"{{T}}/{name}", driver=_tmpfs(S, steps), check=_nothing_left([])))
    track = ["--track", "{T}/t.csv", "--results", "{T}/r.txt"]
    steps = [[*run[:1], short, *run[1:], *track], [*run[:1], long, *run[1:], *track, "--out", "/dev/null"]]
    alone = [[*run[:1], long, *run[1:], "--track", "{T}/t.csv"]]
    clip = [["synth", "contour", "--out", "{T}/c", "--frames", "2", "--size", "96x72", "-q"],
            ["synth", "contour", "--out", "{T}/c", "--frames", "400", "--size", "320x240", "-q"]]
    out += [
        S.Scenario("#47-1 run --track over an earlier track on a full tmpfs", _shown(steps), mention="is kept",
                   driver=_tmpfs(S, steps, "24k"), check=_earlier_kept("t.csv")),
        S.Scenario("#47-1 run --track on a full tmpfs, no earlier file (whole rows kept)", _shown(alone),
                   mention="{T}/t.csv", driver=_tmpfs(S, alone, "12k"), check=_nothing_left(["t.csv"])),
        S.Scenario("#47-1 synth over an earlier clip on a full tmpfs", _shown(clip), mention="No space left",
                   driver=_tmpfs(S, clip, "96k"), check=_clip_kept),
    ]
    return out


def _shown(steps):
    """The last step as the table shows it (the tmpfs as ``T``)."""
    return [a.replace("{T}", "T") for a in steps[-1]]


def _clip_kept(w, res):
    first, last = res.steps
    if first["code"] != 0:
        return "harness error", f"the earlier clip was not written: {first['err'][-80:]}"
    if last["files"] != first["files"]:
        return "data loss", f"the tmpfs holds {sorted(last['files'])}, changed from {sorted(first['files'])}"
    return None


# ---------------------------------------------------------------- 2: sizes checked before work starts


def _sizes(S):
    def made_nothing(*names):
        def check(w, res):
            made = [n for n in names if (w / n).exists()]
            return ("silent wrong", f"{made[0]} was made before the refusal") if made else None

        return check

    fast = S.fast(30)
    return [
        S.Scenario("#47-2 eval --runs 100000000", S.sub(S.EV("{fx}/suite"), "--runs", "100000000"), mention="runs",
                   check=S.all_of(fast, made_nothing("R"))),
        S.Scenario("#47-2 eval --particles 10,20,30,40 --runs 1000000 (the grid, not one size)",
                   S.sub(S.sub(S.EV("{fx}/suite"), "--runs", "1000000"), "--particles", "10,20,30,40"), mention="grid",
                   check=fast),
        S.Scenario("#47-2 synth-suite --clips 1000000000000", ["synth-suite", "--kind", "contour", "--clips",
                                                               "1000000000000", "--frames", "1", "--size", "64x48",
                                                               "--out", "{w}/s"],
                   mention="clips", check=S.all_of(fast, made_nothing("s"))),
        S.Scenario("#47-2 synth-suite --clips 3 (lazy names, a suite as before)",
                   ["synth-suite", "--kind", "contour", "--clips", "3", "--frames", "2", "--size", "96x72", "--seed",
                    "99", "--out", "{w}/s", "-q"], "ok", check=S.suite_holds(["contour-99", "contour-100",
                                                                             "contour-101"])),
        S.Scenario("#47-2 run --targets 100000", S.R("{fx}/plate", "--targets", "100000", init=False),
                   mention="targets", check=fast),
        S.Scenario("#47-2 run --targets 1000 on 160x120 frames", S.R("{fx}/plate", "--targets", "1000", init=False),
                   mention="plates", check=fast),
        S.Scenario("#47-2 reproduce bearings --steps 1000000000", S.sub(S.BE, "--steps", "1000000000"),
                   mention="steps", check=fast),
        S.Scenario("#47-2 reproduce bearings --runs 1000000000", S.sub(S.BE, "--runs", "1000000000"),
                   mention="runs", check=fast),
        S.Scenario("#47-2 reproduce landmarks --steps 1000000000",
                   ["reproduce", "landmarks", "--steps", "1000000000", "--runs", "2", "--in-process", "--out",
                    "{w}/L", "-q"], mention="steps", check=fast),
        S.Scenario("#47-2 reproduce contour --runs 100000000 (before making clips)",
                   ["reproduce", "contour", "--runs", "100000000", "--clips", "{w}/made", "--make", "2", "--frames",
                    "3", "--size", "96x72", "--in-process", "--out", "{w}/C", "-q"], mention="grid",
                   check=S.all_of(fast, made_nothing("made", "C"))),
    ]


# ---------------------------------------------------------------- 3: the Python API


def _python(S, body):
    """A driver: :data:`API` with ``body`` (indented into its ``try``) in a fresh interpreter."""

    def driver(w, argv, timeout):
        code = API.format(body="\n".join("    " + ln for ln in body.strip().splitlines()))
        t0 = time.time()
        try:
            p = subprocess.run([sys.executable, "-c", code], cwd=w, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return S.Result(None, "", "", time.time() - t0, timeout=True)
        return S.Result(p.returncode, p.stdout, p.stderr, time.time() - t0)

    return driver


def _not_wrong(w, res):
    return ("silent wrong", res.out.strip()[:100]) if "SILENT WRONG" in res.out else None


def _api(S):
    same = """
ref = track(frames)
got = track([{conv} for f in frames])
if got != ref:
    print("SILENT WRONG: another track than the uint8 frames'")
"""
    conversions = {"float 0..1": "f.astype(np.float64) / 255", "float 0..255": "f.astype(np.float32)",
                   "uint16": "f.astype(np.uint16) * 257", "int64": "f.astype(np.int64)", "nested lists": "f.tolist()",
                   "BGRA": "cv2.cvtColor(f, cv2.COLOR_BGR2BGRA)"}
    out = [S.Scenario(f"#47-3 Tracker frames as {k}", ["python-api"], "ok", driver=_python(S, same.format(conv=v)),
                      check=_not_wrong) for k, v in conversions.items()]
    out.append(S.Scenario("#47-3 Tracker grey (H, W, 1) frames", ["python-api"], "ok", check=_not_wrong,
                          driver=_python(S, """
grey = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames]
if track([g[:, :, None] for g in grey]) != track(grey):
    print("SILENT WRONG: (H, W, 1) tracks otherwise than (H, W)")
""")))
    refused = {"a bool frame": ("track([f > 0 for f in frames])", "bool"),
               "an int64 frame over 255": ("track([f.astype(np.int64) * 3 for f in frames])", "0..255"),
               "a NaN frame": ("track([np.full((90, 120, 3), np.nan)] * 2)", "NaN"),
               "a 2-channel frame": ("track([f[:, :, :2] for f in frames])", "shape"),
               "colour, then grey": ("track(frames[:1] + [cv2.cvtColor(frames[1], cv2.COLOR_BGR2GRAY)])", "grey"),
               "a frame-size change": ("track(frames[:1] + [frames[1][:80]])", "120x80"),
               "a 3-value box": ("vistrack.Tracker().init(frames[0], (1, 2, 3))", "four numbers"),
               "seed=-1": ("vistrack.Tracker(seed=-1)", "seed"),
               "frobnicate=3": ("vistrack.Tracker(frobnicate=3)", "frobnicate"),
               "particles=2.5": ("vistrack.Tracker(particles=2.5)", "particles"),
               "ess_threshold=nan": ("vistrack.Tracker(ess_threshold=float('nan'))", "ess_threshold"),
               "ess_threshold=5": ("vistrack.Tracker(ess_threshold=5)", "ess_threshold"),
               "ess_threshold=-1": ("vistrack.Tracker(ess_threshold=-1)", "ess_threshold")}
    out += [S.Scenario(f"#47-3 Tracker with {k}", ["python-api"], mention=m, driver=_python(S, body))
            for k, (body, m) in refused.items()]
    return out


# ---------------------------------------------------------------- 4: TraX and Ctrl-C


def _trax(S, case):
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


def _stdin(S, text):
    def driver(w, argv, timeout):
        t0 = time.time()
        p = subprocess.run([sys.executable, "-m", "vistrack.cli", *argv], cwd=w, input=text, capture_output=True,
                           text=True, timeout=timeout)
        return S.Result(p.returncode, p.stdout, p.stderr, time.time() - t0)

    return driver


def _interrupt_at(S, where):
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


def _trax_and_signals(S):
    return [
        S.Scenario("#47-4 trax --model nonsense", ["trax", "--model", "nonsense"], mention="nonsense", check=_no_hello,
                   driver=_stdin(S, "")),
        S.Scenario("#47-4 trax --algo pf-eis", ["trax", "--algo", "pf-eis"], mention="pf-eis", check=_no_hello,
                   driver=_stdin(S, "")),
        S.Scenario("#47-4 trax -n 0", ["trax", "-n", "0"], mention="particles", check=_no_hello, driver=_stdin(S, "")),
        S.Scenario("#47-4 trax, nothing on stdin", ["trax"], mention="TraX client", driver=_stdin(S, "")),
        S.Scenario("#47-4 trax, garbage on stdin", ["trax"], mention="TraX client", driver=_stdin(S, "garbage\n" * 3)),
        *[S.Scenario(f"#47-4 trax session error: {case}", ["trax"], mention=m, driver=_trax(S, case))
          for case, m in (("outside", "outside"), ("missing", "nothere.png"), ("size", "started on"))],
        S.Scenario("#47-4 Ctrl-C while the command line loads", ["--version"], "ok", codes=(130,), check=_aborted,
                   driver=_interrupt_at(S, "start-up")),
        S.Scenario("#47-4 Ctrl-C while the process ends", ["--version"], "ok", codes=(130,), check=_aborted,
                   driver=_interrupt_at(S, "shut-down")),
        S.Scenario("#47-4 Ctrl-C while trax waits for its client", ["trax"], "ok", codes=(130,), check=_aborted,
                   driver=_trax_waiting(S)),
        S.Scenario("#47-4 Ctrl-C 0.3 s into eval", S.EV("{fx}/suite"), "ok", codes=(130,), check=_aborted,
                   driver=S.signals([signal.SIGINT], _after(0.3))),
    ]


def _trax_waiting(S):
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


def _after(seconds):
    t = []

    def ready(w):
        t.append(time.time())
        return t[-1] - t[0] >= seconds

    return ready


# ---------------------------------------------------------------- 5: clips given as URLs (issue 46's)


def _served(S, steps):
    """A driver: ``w/www`` served over HTTP on a free port (``{url}``) while the steps run, with
    ``$VISTRACK_CACHE`` in ``w``; ``then(w)`` between steps. The result is the last step's; every
    step's is in ``res.steps``."""

    def driver(w, argv, timeout):
        handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(w / "www"))
        handler.log_message = lambda *a: None
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        threading.Thread(target=server.serve_forever, daemon=True).start()
        url = f"http://127.0.0.1:{server.server_address[1]}"
        env = {**os.environ, "VISTRACK_CACHE": str(w / "cache")}
        t0, results = time.time(), []
        try:
            for step in steps:
                if callable(step):
                    step(w)
                    continue
                args = [a.format(w=w, fx=S.FX, url=url) for a in step]
                r = S.vistrack(args, w, timeout, env=env)
                results.append(r)
        finally:
            server.shutdown()
        res = results[-1]
        res.steps = results
        res.seconds = time.time() - t0
        return res

    return driver


def _shift_truth(w):
    """The server's ground truth changes: every box 30 px to the right."""
    import csv

    p = w / "www" / "c1" / "groundtruth.csv"
    with open(p, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r["cx"] = f"{float(r['cx']) + 30:.3f}"
    with open(p, "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=list(rows[0]))
        wr.writeheader()
        wr.writerows(rows)


def _fresh_scores(w, res):
    a, b = (json.loads((w / d / "results.json").read_text())["results"][0]["success_auc"] for d in ("R1", "R2"))
    if a == b and "cache" not in res.err.lower():
        return "silent wrong", f"the changed clip scored as the old one (AUC {a:.3f}), no word of a cache"
    return None


def _urls(S):
    ev = ["eval", "{url}/c1", "--model", "contour", "--algos", "bootstrap", "--particles", "20", "--runs", "1",
          "--in-process", "-q", "--out"]
    shown = [a.replace("{url}", "URL") for a in ev] + ["W/R2"]
    return [
        S.Scenario("#47-5 eval a URL clip whose ground truth changed on the server", shown, "ok",
                   prepare=lambda w: shutil.copytree(S.FX / "suite" / "c1", w / "www" / "c1"),
                   check=_fresh_scores,
                   driver=_served(S, [[*ev, "{w}/R1"], _shift_truth, [*ev, "{w}/R2"]])),
        S.Scenario("#47-7 eval an unreachable URL names it", S.EV("http://127.0.0.1:9/c1"), mention="127.0.0.1:9/c1"),
        S.Scenario("#47-7 run 0 beside a file 0 reads the file", ["run", "0", "--init", S.INIT, "-n", "20", "-q",
                                                                  "--track", "{w}/t.csv"], "ok",
                   prepare=lambda w: shutil.copy(S.FX / "v.avi", w / "0"), check=S.track_has(S.FRAMES, S.FRAMES)),
    ]


# ---------------------------------------------------------------- 6: run's summary against eval's


def _summary_agrees(w, res):
    import re

    if res.code != 0:
        return None
    line = next((ln for ln in res.steps[0].out.splitlines() if ln.startswith("vs ground truth")), "")
    r = json.loads((w / "E" / "results.json").read_text())["results"][0]
    m = re.search(r"precision@20px ([0-9.]+).* in (\d+) frames$", line)
    if not m:
        return "silent wrong", f"no summary line: {line[:80]!r}"
    prec, lost = float(m.group(1)), int(m.group(2))
    n = sum(1 for _ in open(w / "mt" / "bad12.txt"))
    if abs(prec - r["precision_20px"]) > 1e-3 or abs(lost / n - r["p_lost"]) > 1e-6:
        return "silent wrong", f"run: precision {prec}, {lost} lost; eval: {r['precision_20px']:.3f}, P(lost) " \
                               f"{r['p_lost']:.3f}"
    res.note = f"precision {prec}, {lost} lost in both"
    return None


def _two_steps(S, first, then_argv):
    def driver(w, argv, timeout):
        a = S.vistrack([x.format(w=w, fx=S.FX) for x in first], w, timeout)
        b = S.vistrack([x.format(w=w, fx=S.FX) for x in then_argv], w, timeout)
        b.steps = [a, b]
        if a.code != 0:
            b.code, b.err = a.code, a.err
        return b

    return driver


def _summary(S):
    first = ["run", "{fx}/bad12", "--init-gt", "-n", "50", "--results", "{w}/mt/bad12.txt"]
    then = ["eval", "{fx}/bad12", "--algos", "", "--results-dir", "{w}/mt", "--out", "{w}/E", "-q"]
    return [S.Scenario("#47-6 run's summary and eval score 12 undecodable frames alike", then, "ok",
                       prepare=lambda w: (w / "mt").mkdir(), driver=_two_steps(S, first, then), check=_summary_agrees)]


# ---------------------------------------------------------------- 7: the minor and wording cases


def _has_column(name):
    def check(w, res):
        if res.code != 0:
            return None
        head = (w / "t.csv").read_text().splitlines()[0].split(",")
        return None if name in head else ("silent wrong", f"the track has no {name} column: {head}")

    return check


def _absent_truth(w, res):
    import numpy as np

    if res.code != 0:
        return None
    gt = np.loadtxt(w / "o" / "groundtruth_rect.txt", delimiter=",")
    if np.any(gt[:, 2] > 0):
        return "silent wrong", f"{int(np.sum(gt[:, 2] > 0))} boxes marked present, all out of the frame"
    return None


def _perturbed_twice(S):
    def prepare(w):
        r = S.vistrack(["synth", "perturb", str(S.FX / "otb"), "--out", str(w / "o"), "--blur", "3", "-q"], w, 300)
        assert r.code == 0, r.err

    return prepare


def _minor(S):
    P = ["synth", "perturb", "{fx}/otb", "--out", "{w}/o", "-q"]

    def tiny(w):
        shutil.copytree(S.FX / "otb", w / "tiny")
        (w / "tiny" / "groundtruth_rect.txt").write_text("1,1,0.5,0.5\n" * 12)

    return [
        S.Scenario("#47-7 run --init-gt, first boxes missing: the redetected column",
                   S.R("{fx}/otb_late", "--init-gt", init=False), "ok", check=_has_column("redetected")),
        S.Scenario("#47-7 synth perturb --gain without --light", [*P, "--gain", "0.5:1"], mention="--light"),
        S.Scenario("#47-7 synth perturb --shake 1000", [*P, "--shake", "1000"], "ok",
                   check=S.all_of(_absent_truth, S.warns("out of the frame"))),
        S.Scenario("#47-7 synth perturb into its own earlier output", [*P, "--blur", "5"], "ok",
                   prepare=_perturbed_twice(S)),
        S.Scenario("#47-7 run a 0.5x0.5 ground-truth box", S.R("{w}/tiny", "--init-gt", init=False),
                   mention="smaller than 2 px", prepare=tiny),
        S.Scenario("#47-7 run --init-gt EXISTING_FOLDER", S.R("{fx}/otb", "--init-gt", "{fx}/otb", init=False),
                   mention="is a folder"),
    ]
