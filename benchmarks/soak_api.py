"""The soak's Python-API scenarios (:mod:`soak`): ``vistrack.Tracker`` given frames of every reasonable kind
and arguments it must refuse, each in a fresh interpreter. What they may break: another track than the
uint8 frames', a traceback or a value accepted that makes no sense."""

from __future__ import annotations

import subprocess
import sys
import time

import soak_harness as S


def scenarios():
    """The Python-API scenarios."""
    return _api() + _options()


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

def _python(body):
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

def _api():
    same = """
ref = track(frames)
got = track([{conv} for f in frames])
if got != ref:
    print("SILENT WRONG: another track than the uint8 frames'")
"""
    conversions = {"float 0..1": "f.astype(np.float64) / 255", "float 0..255": "f.astype(np.float32)",
                   "uint16": "f.astype(np.uint16) * 257", "int64": "f.astype(np.int64)", "nested lists": "f.tolist()",
                   "BGRA": "cv2.cvtColor(f, cv2.COLOR_BGR2BGRA)"}
    out = [S.Scenario(f"Tracker frames as {k}", ["python-api"], "ok", driver=_python(same.format(conv=v)),
                      check=_not_wrong) for k, v in conversions.items()]
    out.append(S.Scenario("Tracker grey (H, W, 1) frames", ["python-api"], "ok", check=_not_wrong,
                          driver=_python("""
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
    out += [S.Scenario(f"Tracker with {k}", ["python-api"], mention=m, driver=_python(body))
            for k, (body, m) in refused.items()]
    return out


def _options():
    """Issue 55's Python-API cases: every model option against its declared type and range, NaN included;
    the tracker's attributes before ``init``."""
    refused = {"lambda_template='x'": "vistrack.Tracker(lambda_template='x')",
               "prior_std=-1": "vistrack.Tracker(prior_std=-1)",
               "lambda_template=nan": "vistrack.Tracker(lambda_template=float('nan'))",
               "lost_confidence=2": "vistrack.Tracker(lost_confidence=2)",
               "redetect='yes'": "vistrack.Tracker(redetect='yes')"}
    out = [S.Scenario(f"Tracker with {k}", ["python-api"], mention=k.split("=")[0], driver=_python(body))
           for k, body in refused.items()]
    out.append(S.Scenario("Tracker attributes before init", ["python-api"], "ok", check=_not_wrong, driver=_python("""
t = vistrack.Tracker()
if (t.box, t.box_estimate, t.visible, t.confidence, t.lost_reason) != (None,) * 5:
    print("SILENT WRONG: an attribute before init is not None")
""")))
    return out
