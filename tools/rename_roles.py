"""Issue 52, item 1 and 3: one word per idea and packages by role, as one mechanical change.

``git mv`` each module to its new name or package, then rewrite every import and every dotted or path
reference in the repository (code, tests, benchmarks, docs, pyproject); names a package re-exported
(``vistrack.filters.FILTERS``, ``vistrack.models.box.Appearance``) are imported from their new home
(:data:`NAME_MOVES`), and the identifiers of :data:`IDENTIFIERS` renamed where they stand as words.
Relative imports inside the package are recomputed from each file's new place. It was run once, from
the repository root, on the commit before the move; kept as the record of that change (the old names
are gone, so running it again does nothing useful). The two compiled kernels the appearance code
read from the box model's kernels (``box_loglik``, ``map_scores``) were moved by hand in the same
commit, as were the package ``__init__`` files.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

MOVES = {
    # system: the process (memory and disk budgets, signals, the compile notice)
    "vistrack.core.runtime": "vistrack.system.resources",
    "vistrack.track.signals": "vistrack.system.signals",
    "vistrack.track.compiling": "vistrack.system.compiling",
    # scoring: scores of tracks against ground truth, and their summaries
    "vistrack.core.metrics": "vistrack.scoring.metrics",
    "vistrack.core.mot": "vistrack.scoring.mot",
    "vistrack.core.longterm": "vistrack.scoring.long_term_scores",
    "vistrack.core.summaries": "vistrack.scoring.aggregate",
    # appearance: per-frame feature maps and the appearance cues the families share
    "vistrack.core.features": "vistrack.appearance.features",
    "vistrack.kernels.appearance": "vistrack.appearance.cue_kernels",
    "vistrack.models.box.appearance": "vistrack.appearance.cues",
    "vistrack.models.box.appearance_map": "vistrack.appearance.cue_map",
    "vistrack.models.box.frame_maps": "vistrack.appearance.frame_maps",
    "vistrack.models.box.frame_kernels": "vistrack.appearance.frame_kernels",
    "vistrack.models.box.target_colour": "vistrack.appearance.target_colour",
    "vistrack.models.box.correlation": "vistrack.appearance.correlation",
    "vistrack.models.box.dcf_kernels": "vistrack.appearance.dcf_kernels",
    "vistrack.models.box.feature_kernels": "vistrack.appearance.dcf_feature_kernels",
    # kernels: what the families share; a family's own in its package
    "vistrack.kernels.grid": "vistrack.kernels.map_draws",
    "vistrack.kernels.laplace": "vistrack.models.bearings.laplace_parts",
    # proposals
    "vistrack.proposals.grid": "vistrack.proposals.map_proposal",
    # the frame loop
    "vistrack.track.loop": "vistrack.loop.stepper",
    "vistrack.track.profiling": "vistrack.loop.profiling",
    # session: `vistrack run`, one video with its outputs
    "vistrack.track.plan": "vistrack.session.plan",
    "vistrack.track.run": "vistrack.session.recording",
    "vistrack.track.summary": "vistrack.session.run_summary",
    # api: vistrack as a component (the OpenCV-shaped Tracker, the TraX server)
    "vistrack.track.tracker": "vistrack.api.tracker",
    "vistrack.track.trax": "vistrack.api.trax_server",
    # the registry: filters beside the models
    "vistrack.filters.registry": "vistrack.registry.filter_specs",
    # batch: the Dask cluster and the task files
    "vistrack.engine.grid": "vistrack.batch.cluster",
    "vistrack.engine.tasks": "vistrack.batch.tasks",
    # evaluation: eval's experiment and pipeline
    "vistrack.engine.evaluation": "vistrack.evaluation.experiment",
    "vistrack.engine.multi_target": "vistrack.evaluation.multi_target",
    "vistrack.engine.pipeline": "vistrack.evaluation.pipeline",
    # baselines: the trackers vistrack is compared with
    "vistrack.engine.opencv_trackers": "vistrack.baselines.opencv",
    # reports: eval's files, tables and plots
    "vistrack.engine.report": "vistrack.reports.eval_report",
    "vistrack.engine.mot_report": "vistrack.reports.mot_report",
    "vistrack.engine.plots": "vistrack.reports.plots",
    # the demo
    "vistrack.engine.demo": "vistrack.demo.steps",
    # names that repeated across packages
    "vistrack.cli.grid": "vistrack.cli.progress",
    "vistrack.reproduce.pipeline": "vistrack.reproduce.reproduction",
    "vistrack.reproduce.suite": "vistrack.reproduce.clip_suites",
    "vistrack.reproduce.hs_sir": "vistrack.reproduce.history_sampling",
    "vistrack.data_synth.contour": "vistrack.data_synth.contour_clip",
    "vistrack.data_synth.plate": "vistrack.data_synth.plate_clip",
    "vistrack.data_synth.landmarks": "vistrack.data_synth.landmark_clip",
    "vistrack.data_synth.bearings": "vistrack.data_synth.bearings_sequence",
    "vistrack.data_synth.longterm": "vistrack.data_synth.longterm_clip",
    "vistrack.data_synth.render": "vistrack.data_synth.scene",
    "vistrack.models.plate.fit": "vistrack.models.plate.fitting",
    "vistrack.models.landmarks.video": "vistrack.models.landmarks.video_model",
}
#: names a package re-exported, now imported from their new home: (old package, name) -> new module
NAME_MOVES = {
    **{("vistrack.filters", n): "vistrack.registry" for n in ("ALGORITHMS", "FILTERS", "FilterSpec", "make_filter")},
    **{("vistrack.models.box", n): "vistrack.appearance" for n in ("Appearance", "CorrelationFilter")},
}
#: identifiers renamed (whole words, everywhere): one word per idea in the session and the loop
IDENTIFIERS = {
    "RunPlan": "Plan",
    "plan_run": "prepare",
    "run_plan": "execute",
    "track_video": "record_video",
    "VideoRun": "SessionLog",
}
DELETED = set()
NEW_PACKAGES = {
    "vistrack.system": "The process: memory and disk budgets (:mod:`.resources`), signals (:mod:`.signals`) and the "
                       "compile notice (:mod:`.compiling`).",
    "vistrack.scoring": "Scores of tracks against ground truth and their summaries over runs.",
    "vistrack.appearance": "Per-frame feature maps and the appearance cues the model families share: colour "
                           "histograms against a ring, grey templates, correlation filters.",
    "vistrack.loop": "The frame loop: one filter step per frame, and the timing of its stages.",
    "vistrack.session": "``vistrack run``: one video tracked, with its track file, annotated video and summary.",
    "vistrack.api": "vistrack as a component: the OpenCV-shaped :class:`~vistrack.api.tracker.Tracker` and the "
                    "TraX server.",
    "vistrack.batch": "Running many tasks: the Dask cluster, the task files, the ``--out`` lock and resume.",
    "vistrack.evaluation": "``eval``: its experiment (tasks, runner, scores) and its pipeline.",
    "vistrack.baselines": "The trackers vistrack is compared with (OpenCV's).",
    "vistrack.reports": "``eval``'s files: tables, the HTML report and plots.",
    "vistrack.demo": "``vistrack demo``: its clip, its comparisons and the real-clip step.",
}
SELF = "tools/rename_roles.py"


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
        renamed = [it for it in items if (absbase, it.split(" as ")[0].strip()) in NAME_MOVES]
        if renamed:  # names a package re-exported: imported from their new home, the rest as they were
            rest = [it for it in items if it not in renamed]
            homes = {}
            for it in renamed:
                homes.setdefault(NAME_MOVES[(absbase, it.split(" as ")[0].strip())], []).append(it)
            lines = []
            if rest:
                head = relativize(new_pkg, new_name(absbase)) if relative else new_name(absbase)
                lines.append(f"{m.group('indent')}from {head} import {', '.join(rest)}")
            for home, its in homes.items():
                head = relativize(new_pkg, home) if (relative and relative_ok) else home
                lines.append(f"{m.group('indent')}from {head} import {', '.join(its)}")
            return "\n".join(lines) + comment
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
    return text


def rewrite_identifiers(text):
    """The identifiers of :data:`IDENTIFIERS` where they stand as whole words."""
    pat = re.compile(r"\b(" + "|".join(map(re.escape, IDENTIFIERS)) + r")\b")
    return pat.sub(lambda m: IDENTIFIERS[m.group(1)], text)


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
        new = rewrite_identifiers(rewrite_dotted(new))
        if new != text:
            path.write_text(new)
    for f, dest in sorted(where.items()):
        Path(dest).parent.mkdir(parents=True, exist_ok=True)
        subprocess.run(["git", "mv", f, dest], check=True)
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
