"""Faults of ``vistrack trax``: its options checked before the hello, an absent, broken or dead client and a
bad region each one line and a non-zero exit, session errors told to the client, never a hang."""

from __future__ import annotations

import signal
import subprocess
import sys

import cv2
import pytest

from fault_helpers import (
    api_frames,
    trax_session,
)


def _vistrack(argv, stdin=subprocess.DEVNULL, **kw):
    return subprocess.run([sys.executable, "-m", "vistrack.cli", *argv], stdin=stdin, capture_output=True, text=True,
                          timeout=120, **kw)

def test_trax_checks_its_options_before_the_hello():
    p = _vistrack(["trax", "--model", "nonsense"])
    assert p.stdout == "" and p.stderr.startswith("Error: unknown model 'nonsense'") and p.stderr.count("\n") == 1
    p = _vistrack(["trax", "--algo", "pf-eis"])
    assert p.stdout == "" and "does not run on the box model" in p.stderr and p.stderr.count("\n") == 1

@pytest.mark.parametrize("stdin", ["", "garbage\n", "@@TRAX:frame\n"], ids=["nothing", "garbage", "out of order"])
def test_trax_answers_an_absent_or_broken_client_with_one_line(stdin):
    pytest.importorskip("trax", reason="vot-trax is not installed")
    p = _vistrack(["trax"], stdin=None, input=stdin)
    assert p.returncode == 1 and p.stdout.startswith("@@TRAX:hello")
    assert p.stderr.startswith("Error: no TraX client") and p.stderr.count("\n") == 1, p.stderr

@pytest.mark.parametrize("case, words", [
    ("outside", "start box 500,500,10,10 lies outside the 120x90 frame"),
    ("missing", "cannot read the frame {d}/nothere.png: no such file"),
    ("size", "this frame is 120x80 colour, but the tracker started on 120x90 colour frames"),
])
def test_trax_session_errors_reach_the_client_and_no_traceback(tmp_path, case, words):
    pytest.importorskip("trax", reason="vot-trax is not installed")
    f = api_frames(1)[0]
    cv2.imwrite(str(tmp_path / "f0.png"), f)
    cv2.imwrite(str(tmp_path / "f1.png"), f[:80])
    box = (500, 500, 10, 10) if case == "outside" else (30, 30, 25, 25)
    second = {"outside": None, "missing": tmp_path / "nothere.png", "size": tmp_path / "f1.png"}[case]
    code, err, heard = trax_session(tmp_path / "f0.png", box, second)
    words = words.format(d=tmp_path)
    assert isinstance(heard, str) and words in heard  # the client was told why
    assert code == 1 and err.startswith(f"Error: {words}") and err.count("\n") == 1 and "Traceback" not in err

def test_ctrl_c_while_trax_waits_for_its_client_is_aborted_and_130():
    pytest.importorskip("trax", reason="vot-trax is not installed")

    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", "trax"], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert proc.stdout.readline().startswith("@@TRAX:hello")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and err.strip() == "Aborted."
