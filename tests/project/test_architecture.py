"""The shape of the code (docs/architecture.md): the command line parses, calls the library and prints;
every module sits in a package; no module imports another's private names; the task-file path, the
equal-time timing and the algorithm names each live in one place."""

from __future__ import annotations

import ast
import functools
import importlib
import re

from path_helpers import ROOT as REPO
from vistrack.registry import BASELINES, FILTERS, LAYOUTS, MODELS, comparisons
from vistrack.reproduce.tables import TABLES

ROOT = REPO / "vistrack"
ARCHITECTURE = ROOT.parent / "docs" / "architecture.md"
MAX_COMMAND_LINES = 25


@functools.cache
def _parsed():
    return tuple((p.relative_to(ROOT).as_posix(), ast.parse(p.read_text(encoding="utf-8")))
                 for p in sorted(ROOT.rglob("*.py")))


def _modules():
    """``(path under vistrack/, its syntax tree)`` of every module, parsed once per test process."""
    yield from _parsed()


def _is_command(fn):
    """A click command or group: decorated by ``click.command``, ``<group>.command`` or ``.group``."""
    for d in fn.decorator_list:
        f = d.func if isinstance(d, ast.Call) else d
        if isinstance(f, ast.Attribute) and f.attr in ("command", "group"):
            return True
    return False


def test_each_command_body_is_at_most_25_lines():
    """Below its option decorators and its help (the docstring), a command parses, calls the library and
    prints: at most 25 lines."""
    long = []
    for name, tree in _modules():
        if not name.startswith("cli/"):
            continue
        for fn in ast.walk(tree):
            if isinstance(fn, ast.FunctionDef) and _is_command(fn):
                body = fn.body[1:] if ast.get_docstring(fn) is not None else fn.body
                lines = body[-1].end_lineno - body[0].lineno + 1 if body else 0
                if lines > MAX_COMMAND_LINES:
                    long.append(f"{name}:{fn.name} {lines} lines")
    assert long == []


def test_every_module_sits_in_a_package():
    assert sorted(p.name for p in ROOT.glob("*.py")) == ["__init__.py"]


def test_no_module_imports_a_private_name_of_another():
    found = []
    for name, tree in _modules():
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module != "__future__":
                found += [f"{name}:{node.lineno} {a.name}" for a in node.names
                          if a.name.startswith("_") and not a.name.startswith("__")]
    assert found == []


@functools.cache
def _constant_lines(tree):
    """``{value: [line, ...]}`` of the constants in ``tree``."""
    out = {}
    for n in ast.walk(tree):
        if isinstance(n, ast.Constant):
            out.setdefault(n.value, []).append(n.lineno)
    return out


def _constants(tree, value):
    return _constant_lines(tree).get(value, [])


def test_the_task_file_path_is_built_in_one_function():
    """``OUT/tasks/<name>.json`` is :func:`vistrack.batch.tasks.task_path`'s alone: every runner, the
    engine and every results loader go through it."""
    where = {name: lines for name, tree in _modules() if (lines := _constants(tree, "tasks"))}
    assert list(where) == ["batch/tasks.py"] and len(where["batch/tasks.py"]) == 1
    tree = dict(_modules())["batch/tasks.py"]
    fn = next(f for f in tree.body if isinstance(f, ast.FunctionDef) and f.name == "task_path")
    assert fn.lineno <= where["batch/tasks.py"][0] <= fn.end_lineno


def test_the_equal_time_timing_and_solving_are_one_function_each():
    """Every equal-time comparison (eval, the history-sampling, several-plate and bearings reproductions)
    goes through :func:`vistrack.scoring.metrics.equal_time`, which alone solves for N, and times with
    :func:`~vistrack.scoring.metrics.best_ms`, the one timing loop."""
    solvers, timers = {}, {}
    for name, tree in _modules():
        for node in ast.walk(tree):
            if isinstance(node, ast.Call):
                f = node.func.id if isinstance(node.func, ast.Name) else getattr(node.func, "attr", "")
                if f in ("equal_time_n", "equal_time_search"):
                    solvers.setdefault(name, []).append(node.lineno)
                if f == "best_ms":
                    timers.setdefault(name, []).append(node.lineno)
    assert list(solvers) == ["scoring/metrics.py"]
    assert set(timers) == {"loop/stepper.py", "evaluation/multi_target.py", "reproduce/bearings.py"}
    callers = {name for name, tree in _modules() for n in ast.walk(tree)
               if isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "equal_time"}
    assert callers == {"evaluation/pipeline.py", "evaluation/multi_target.py", "reproduce/history_sampling.py",
                       "reproduce/bearings.py"}


def test_no_algorithm_list_outside_the_registry():
    """Algorithm names appear in the filter registry, each filter's own module (its ``name``) and the
    registry's comparisons of the seeds, nowhere else (a reproduction's name such as ``hs-sir`` aside)."""
    names = set(FILTERS) - set(TABLES)
    found = [f"{name}:{line}" for name, tree in _modules()
             if not name.startswith(("filters/", "registry/")) for a in names for line in _constants(tree, a)]
    assert found == []


def test_the_seeds_comparisons_name_registered_algorithms():
    entries = [*comparisons.CONTOUR, *comparisons.HISTORY_SAMPLING, *comparisons.PLATE, *comparisons.PLATES,
               *comparisons.DEMO]
    algos = [a for a, _ in entries] + list(comparisons.BEARINGS) + list(comparisons.SEED_000_ORDER)
    algos += [a for k in comparisons.LANDMARKS.values() for a in k]
    assert set(algos) <= set(FILTERS)
    assert all(isinstance(n, int) and n > 0 for _, n in entries)


def test_no_tracker_or_layout_list_outside_the_registry():
    """A comparison tracker's name appears in the registry alone (its entry, what the seeds and the demo
    compare); no module outside the registry and the plate family lists two plate layouts (``--layout``'s
    choices are the registry's ``LAYOUTS``)."""
    trackers = [f"{name}:{line}" for name, tree in _modules() if not name.startswith("registry/")
                for a in BASELINES for line in _constants(tree, a)]
    assert trackers == []
    layouts = [f"{name}:{node.lineno}" for name, tree in _modules()
               if not name.startswith(("registry/", "models/plate/")) for node in ast.walk(tree)
               if isinstance(node, (ast.List, ast.Tuple, ast.Set, ast.Dict))
               and len({e.value for e in (node.keys if isinstance(node, ast.Dict) else node.elts)
                        if isinstance(e, ast.Constant) and e.value in LAYOUTS}) > 1]
    assert layouts == []


def _text(node):
    return ast.unparse(node)


def test_no_branch_on_a_model_name_outside_its_family():
    """No ``model == "box"``-style test outside the registry and that model's own package: what a summary or
    a report needs of a model is in its registry entry (``ModelSpec``). Nor does a module outside the registry
    and the families list two models' names (the compile times, for one, are each entry's); the
    reproductions' experiments and the synthetic clip kinds, named after the models they are for, are their
    own lists (``reproduce/``, ``data_synth/``)."""
    branches, lists = [], []
    for name, tree in _modules():
        for node in ast.walk(tree):
            if isinstance(node, ast.Compare):
                sides = [node.left, *node.comparators]
                named = {e.value for s in sides for e in ast.walk(s) if isinstance(e, ast.Constant)
                         and e.value in MODELS}
                if named and "model" in _text(node) and not name.startswith("registry/") and not all(
                        name.startswith(f"models/{m}/") for m in named):
                    branches.append(f"{name}:{node.lineno} {_text(node)}")
            if isinstance(node, (ast.List, ast.Tuple, ast.Set, ast.Dict)) and not name.startswith(
                    ("registry/", "models/", "reproduce/", "data_synth/")):
                elts = node.keys if isinstance(node, ast.Dict) else node.elts
                if len({e.value for e in elts if isinstance(e, ast.Constant) and e.value in MODELS}) > 1:
                    lists.append(f"{name}:{node.lineno}")
    assert branches == [] and lists == []


def test_file_names_repeat_only_in_the_family_roles():
    """No two modules of vistrack/ share a file name, but the roles parallel model families hold, as
    docs/architecture.md lists them (each family's ``model.py``, ...)."""
    text = ARCHITECTURE.read_text(encoding="utf-8")
    roles = set(re.findall(r"`(\w+\.py)`", text.split("A file name repeats only")[1].split("\n\n")[0]))
    names = {}
    for p in ROOT.rglob("*.py"):
        if p.name != "__init__.py":
            names.setdefault(p.name, []).append(p.relative_to(ROOT).as_posix())
    repeated = {n: sorted(where) for n, where in names.items() if len(where) > 1 and n not in roles}
    assert repeated == {}
    families = {n: where for n, where in names.items() if n in roles}
    assert all(w.startswith("models/") and w.count("/") == 2 for where in families.values() for w in where)


def _stems(name):
    """The words of an exported name, each cut to its stem (``Stepper`` and ``step_frames`` share ``step``)."""
    words = re.findall(r"[A-Z]+(?![a-z])|[A-Z]?[a-z]+|\d+", name)
    out = set()
    for w in (w.lower() for w in words):
        for suffix in ("ing", "er", "ed", "s"):
            if w.endswith(suffix) and len(w) - len(suffix) >= 3:
                w = w[:-len(suffix)]
                break
        out.add(w[:-1] if len(w) > 3 and w[-1] == w[-2] else w)
    return out


def test_the_run_loop_and_api_exports_share_no_stem():
    """What was ``track/`` (``track()``, ``Tracker``, ``track_video``, ``RunPlan``, ``run_plan``, ``plan_run``) is
    now three packages, and the names they export share no word: one word per idea."""
    seen, shared = {}, []
    for package in ("vistrack.session", "vistrack.loop", "vistrack.api"):
        for name in importlib.import_module(package).__all__:
            for stem in _stems(name):
                if stem in seen:
                    shared.append(f"{seen[stem]} and {package}.{name} share {stem!r}")
                seen[stem] = f"{package}.{name}"
    assert _stems("FrameStepper") & _stems("step_frames") == {"frame", "step"}
    assert shared == []


def _table_rows(text, first_cell):
    """``{name: the line's text}`` of the markdown table whose header starts with ``| first_cell |``."""
    table = text.split(f"| {first_cell} |", 1)[1].split("\n\n", 1)[0]
    return {m.group(1): m.group(2) for m in re.finditer(r"^\| `([\w]+)/` \| (.*) \|$", table, re.M)}


def test_every_module_is_named_in_its_package_line():
    """docs/architecture.md names every module's package and role: each package of vistrack/ has a line in
    its layer table (each model family in the families' table), the line names every module of the package,
    and holds one role (no "also")."""
    text = ARCHITECTURE.read_text(encoding="utf-8")
    layers, families = _table_rows(text, "layer"), _table_rows(text, "family")
    missing, mixed = [], [name for name, line in {**layers, **families}.items() if re.search(r"\balso\b", line)]
    for p in sorted(ROOT.rglob("*.py")):
        parts = p.relative_to(ROOT).parts
        if len(parts) == 1 or p.name == "__init__.py":
            continue
        family = parts[0] == "models" and len(parts) == 3
        line = (families if family else layers).get(parts[1] if family else parts[0])
        if line is None or not re.search(rf"`{re.escape(p.stem)}`|\b{re.escape(p.stem)}\b", line):
            missing.append("/".join(parts))
    assert missing == [] and mixed == []
    assert set(layers) == {p.name for p in ROOT.iterdir() if (p / "__init__.py").is_file()}
