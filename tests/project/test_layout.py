"""The code's shape (issue 36): no module in vistrack/ over 400 lines, no function over 60."""

import ast

from path_helpers import ROOT as REPO

ROOT = REPO / "vistrack"


def test_no_module_over_400_lines():
    long = {str(p.relative_to(ROOT)): n for p in ROOT.rglob("*.py")
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > 400}
    assert long == {}


def test_no_function_over_60_lines():
    long = []
    for p in ROOT.rglob("*.py"):
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.end_lineno - node.lineno >= 60:
                long.append(f"{p.relative_to(ROOT)}:{node.lineno} {node.name} ({node.end_lineno - node.lineno + 1})")
    assert long == []


def test_no_probes_for_optional_parts():
    """Optional parts are protocols checked with ``offers`` (vistrack/core/hooks.py, the one place that
    looks); nothing else asks ``hasattr`` or ``getattr(x, name, default)`` of a model, a filter, a
    proposal or an observation (vistrack/baselines/opencv.py looks for OpenCV's trackers in ``cv2``)."""
    allowed = {"core/hooks.py", "baselines/opencv.py"}
    probes = []
    for p in ROOT.rglob("*.py"):
        if str(p.relative_to(ROOT)) in allowed:
            continue
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and (
                    node.func.id == "hasattr" or (node.func.id == "getattr" and len(node.args) == 3)):
                probes.append(f"{p.relative_to(ROOT)}:{node.lineno}")
    assert probes == []
