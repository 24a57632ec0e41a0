"""Issue 45, item 3: move vistrack's top-level modules into packages that show the layers.

One mechanical change: ``git mv`` each module, then rewrite every import and every dotted or path
reference in the repository (code, tests, benchmarks, docs, pyproject). Relative imports inside the
package are recomputed from each file's new place. It was run once, from the repository root, on
the commit before the move; it is kept as the record of that change (running it again does nothing
useful: the old names are gone).

The next commits moved by hand: ``vistrack.models.builders`` -> ``vistrack.registry.builders``,
``vistrack.models.registry`` -> ``vistrack.registry.catalog`` (``vistrack.registry`` re-exports both),
``vistrack.reproduce.multi_plate``'s tasks and scores -> ``vistrack.evaluation.multi_target``,
``vistrack.cli.demo``'s clips and comparisons -> ``vistrack.demo.steps``, ``vistrack.filters.ALGORITHMS``
-> ``vistrack.registry.filter_specs`` (re-exported), ``check_particle_memory`` -> ``vistrack.registry``.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

MOVES = {
    # core: numpy, scipy, OpenCV, numba only
    "vistrack.particles": "vistrack.core.particles",
    "vistrack.resampling": "vistrack.core.resampling",
    "vistrack.gaussian": "vistrack.core.gaussian",
    "vistrack.transition": "vistrack.core.transition",
    "vistrack.hooks": "vistrack.core.hooks",
    "vistrack.features": "vistrack.appearance.features",
    "vistrack.metrics": "vistrack.scoring.metrics",
    "vistrack.mot": "vistrack.scoring.mot",
    "vistrack.runtime": "vistrack.system.resources",
    # io: videos, clips, the files a run reads and writes
    "vistrack.video": "vistrack.io.video",
    "vistrack.video_errors": "vistrack.io.video_errors",
    "vistrack.video_writer": "vistrack.io.video_writer",
    "vistrack.clips": "vistrack.io.clips",
    "vistrack.remote": "vistrack.io.remote",
    "vistrack.starts": "vistrack.io.starts",
    "vistrack.track_files": "vistrack.io.track_files",
    "vistrack.results_format": "vistrack.io.results_format",
    "vistrack.outputs": "vistrack.io.outputs",
    "vistrack.render": "vistrack.io.render",
    # a model by name
    "vistrack.builders": "vistrack.models.builders",
    "vistrack.models.kernel": "vistrack.core.transition",
    # one run: the frame loop, the session, the OpenCV-shaped Tracker, TraX
    "vistrack.tracking": "vistrack.loop.stepper",
    "vistrack.session": "vistrack.session.recording",
    "vistrack.run_summary": "vistrack.session.run_summary",
    "vistrack.signals": "vistrack.system.signals",
    "vistrack.profiling": "vistrack.loop.profiling",
    "vistrack.tracker": "vistrack.api.tracker",
    "vistrack.trax": "vistrack.api.trax_server",
    # the batch engine
    "vistrack.engine": "vistrack.batch.cluster",
    "vistrack.tasks": "vistrack.batch.tasks",
    "vistrack.evaluation": "vistrack.evaluation.experiment",
    "vistrack.report": "vistrack.reports.eval_report",
    "vistrack.mot_report": "vistrack.reports.mot_report",
    "vistrack.plots": "vistrack.reports.plots",
    # near-collisions renamed
    "vistrack.reproduce.report": "vistrack.reproduce.tables",
    "vistrack.reproduce.plates": "vistrack.reproduce.multi_plate",
    "vistrack.filters.partitioning": "vistrack.filters.partition_step",
}
#: re-exports removed (their importers now import the module itself)
DELETED = {"vistrack.models.kernel"}
NEW_PACKAGES = {
    "vistrack.core": "The core: particle sets, resampling, Gaussians, the step's kernel, per-frame feature maps, "
                     "metrics and process settings (numpy, scipy, OpenCV and numba only).",
    "vistrack.io": "Videos, clips and the files a run reads and writes: decoding, writing, ground truth, "
                   "start boxes, track CSVs, the toolkits' result files, output paths, drawing.",
    "vistrack.track": "One run: the frame loop, ``vistrack run``'s session and summary, signals, stage timing, "
                      "the OpenCV-shaped Tracker and the TraX server.",
    "vistrack.engine": "The batch engine: Dask tasks and task files, ``eval``'s tasks and summaries, reports "
                       "and plots.",
}
SELF = "tools/move_layers.py"


def mod_path(mod, pkg=False):
    p = Path(*mod.split("."))
    return p / "__init__.py" if pkg else p.with_suffix(".py")


def new_name(mod):
    """The module's new dotted name (prefix-aware: an attribute ``vistrack.video.X`` keeps its tail)."""
    for old in sorted(MOVES, key=len, reverse=True):
        if mod == old or mod.startswith(old + "."):
            return MOVES[old] + mod[len(old):]
    return mod


def file_module(path):
    parts = list(Path(path).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def file_package(path):
    """The package a file's relative imports start from."""
    if path.endswith("__init__.py"):
        return file_module(path)
    return ".".join(Path(path).with_suffix("").parts[:-1])


def resolve(package, dots, mod):
    base = package.split(".")
    if dots > 1:
        base = base[: len(base) - (dots - 1)]
    return ".".join(base + ([mod] if mod else []))


def relativize(package, target):
    p, t = package.split("."), target.split(".")
    common = 0
    while common < min(len(p), len(t)) and p[common] == t[common]:
        common += 1
    return "." * (len(p) - common + 1) + ".".join(t[common:])


IMPORT = re.compile(r"^(?P<indent>[ \t]*)from\s+(?P<base>\.+[\w.]*|vistrack[\w.]*)\s+import\s+"
                    r"(?P<names>\([^)]*\)|[^\n]*)", re.M)


def split_names(names):
    inner = names.strip()
    comment = ""
    if inner.startswith("("):
        inner = inner[1:-1]
    elif "#" in inner:
        inner, comment = inner.split("#", 1)
        comment = "  #" + comment
    return [x.strip() for x in inner.replace("\n", " ").split(",") if x.strip()], comment


def rewrite_imports(text, old_pkg, new_pkg, relative_ok):
    def sub(m):
        base = m.group("base")
        relative = base.startswith(".")
        absbase = resolve(old_pkg, len(base) - len(base.lstrip(".")), base.lstrip(".")) if relative else base
        items, comment = split_names(m.group("names"))
        moved = [it for it in items if absbase + "." + it.split(" as ")[0].strip() in MOVES]
        if moved:  # from PKG import module: import it from its new package
            if len(moved) != len(items):
                raise SystemExit(f"mixed module/name import in {old_pkg}: {m.group(0)!r}")
            lines = []
            for it in items:
                name, _, alias = it.partition(" as ")
                name, alias = name.strip(), alias.strip() or name.strip()
                parent, leaf = MOVES[absbase + "." + name].rsplit(".", 1)
                head = relativize(new_pkg, parent) if (relative and relative_ok) else parent
                lines.append(f"{m.group('indent')}from {head} import {leaf if leaf == alias else f'{leaf} as {alias}'}")
            return "\n".join(lines) + comment
        newbase = new_name(absbase)
        head = relativize(new_pkg, newbase) if relative else newbase
        if head == base:
            return m.group(0)
        start = m.start("base") - m.start()
        return m.group(0)[:start] + head + m.group(0)[start + len(base):]

    return IMPORT.sub(sub, text)


def rewrite_dotted(text):
    """Absolute dotted names and file paths anywhere in the text."""
    olds = sorted(MOVES, key=len, reverse=True)
    pat = re.compile(r"(?<![\w.])(" + "|".join(re.escape(o) for o in olds) + r")(?![\w])")
    text = pat.sub(lambda m: MOVES[m.group(1)], text)
    paths = {mod_path(o).as_posix(): mod_path(n).as_posix() for o, n in MOVES.items()}
    ppat = re.compile(r"(?<![\w/])(" + "|".join(re.escape(o) for o in sorted(paths, key=len, reverse=True)) + r")")
    text = ppat.sub(lambda m: paths[m.group(1)], text)
    # an import already rewritten to vistrack.engine.X must not take engine -> engine.grid a second time
    text = re.sub(r"vistrack\.engine\.grid\.(evaluation|tasks|report|mot_report|plots|grid)\b",
                  r"vistrack.engine.\1", text)
    return re.sub(r"from vistrack\.engine\.grid import (evaluation|tasks|report|mot_report|plots)\b",
                  r"from vistrack.engine import \1", text)


def main():
    tracked = subprocess.run(["git", "ls-files"], capture_output=True, text=True, check=True).stdout.split()
    where = {}
    for f in tracked:
        if f.startswith("vistrack/") and f.endswith(".py"):
            mod = file_module(f)
            if mod in MOVES and mod not in DELETED:
                where[f] = mod_path(MOVES[mod]).as_posix()
    for f in tracked:
        if f == SELF or not f.endswith((".py", ".md", ".toml", ".yml", ".yaml", ".cfg", ".ini")):
            continue
        path = Path(f)
        text = path.read_text()
        new = text
        if f.endswith(".py"):
            new = rewrite_imports(new, file_package(f), file_package(where.get(f, f)),
                                  relative_ok=f.startswith("vistrack/"))
        new = rewrite_dotted(new)
        if new != text:
            path.write_text(new)
    # engine.py becomes engine/grid.py: moved aside first, engine/ being a new package of that name
    subprocess.run(["git", "mv", "vistrack/engine.py", "vistrack/_engine_moving.py"], check=True)
    for f, dest in sorted(where.items()):
        Path(dest).parent.mkdir(parents=True, exist_ok=True)
        src = "vistrack/_engine_moving.py" if f == "vistrack/engine.py" else f
        subprocess.run(["git", "mv", src, dest], check=True)
    for mod in DELETED:
        subprocess.run(["git", "rm", "-qf", mod_path(mod).as_posix()], check=True)
    for pkg, doc in NEW_PACKAGES.items():
        init = mod_path(pkg, pkg=True)
        if not init.exists():
            init.write_text(f'"""{doc}"""\n')
        subprocess.run(["git", "add", init.as_posix()], check=True)
    print(f"moved {len(where)} modules, removed {len(DELETED)}")


if __name__ == "__main__":
    sys.exit(main())
