"""Write the API reference pages (``docs/api/*.md``): one page per package of vistrack, a section per
public module (mkdocstrings ``::: module``), so that the reference covers every public module;
``tests/project/test_docs.py`` checks that it does. Run from the repository root after adding a module::

    python tools/api_pages.py
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
API = ROOT / "docs" / "api"

#: page -> (title, the packages it covers, what it is about); in the order of the layers, top first
PAGES = {
    "vistrack": ("The package", ["vistrack"],
                 "The top level: `vistrack.Tracker`, the particle set and the version (from the packages below)."),
    "cli": ("Command line", ["vistrack.cli"],
            "The `vistrack` command: one module per command; each parses, calls one library function and prints."),
    "reproduce": ("Reproductions", ["vistrack.reproduce"],
                  "The seeds' experiments as batch experiments: their configs, runners, results, tables and "
                  "figures."),
    "demo": ("The demo", ["vistrack.demo"], "`vistrack demo`: its clip, its comparisons and the real-clip step."),
    "evaluation": ("Evaluation", ["vistrack.evaluation"],
                   "`eval`: its experiment (tasks, the runner, scores) and its pipeline."),
    "reports": ("Reports", ["vistrack.reports"], "`eval`'s files: tables, the HTML report and plots."),
    "batch": ("Batch runs", ["vistrack.batch"],
              "Running many tasks: the Dask cluster, the task files, the `--out` lock and resume."),
    "session": ("A run of a video", ["vistrack.session"],
                "`vistrack run`: the plan (model, algorithm, options checked), the recording of the track file and "
                "annotated video, the summary."),
    "api": ("Tracker and TraX", ["vistrack.api"],
            "vistrack as a component: the OpenCV-shaped `vistrack.Tracker` and the TraX server."),
    "baselines": ("Baselines", ["vistrack.baselines"], "The trackers vistrack is compared with."),
    "loop": ("The frame loop", ["vistrack.loop"], "One filter step per frame, and the timing of its stages."),
    "registry": ("Registry", ["vistrack.registry"],
                 "Everything by name: models, filters, comparison trackers and plate layouts, which algorithms run "
                 "on which model, the defaults, building a model by name."),
    "data_synth": ("Synthetic data", ["vistrack.data_synth"],
                   "Synthetic clips and sequences with exact ground truth, stressed copies of real clips."),
    "filters": ("Filters", ["vistrack.filters"],
                "Every filter is a `ParticleFilter` with one `step(particles, obs, rng)`; `make_filter(name, model)` "
                "builds one by its `--algo` name."),
    "models": ("Model protocols and framework", ["vistrack.models"],
               "What a model offers and a filter needs (the protocols), a model's registry entry, partitions, the "
               "lost rule, the toy models."),
    "families": ("Model families", ["vistrack.models.box", "vistrack.models.contour", "vistrack.models.plate",
                                    "vistrack.models.landmarks", "vistrack.models.bearings"],
                 "Each family is a package under `vistrack/models/`: its model, likelihood, proposals, compiled "
                 "kernels and its builder (its registry entry)."),
    "proposals": ("Local proposals", ["vistrack.proposals"], "The local proposals models share."),
    "appearance": ("Appearance", ["vistrack.appearance"],
                   "Per-frame feature maps and the appearance cues the families share: colour against a ring, grey "
                   "templates, correlation filters."),
    "io": ("Videos, clips and files", ["vistrack.io"],
           "Decoding and writing video, clip folders and ground truth, start boxes, track and result files."),
    "scoring": ("Scoring", ["vistrack.scoring"],
                "Scores of tracks against ground truth (errors, lost frames, success and precision, long-term and "
                "multi-target scores) and their summaries over runs."),
    "core": ("Particle core", ["vistrack.core"],
             "Particle sets, resampling, Gaussians, the step's kernel, the optional hooks, random streams."),
    "kernels": ("Compiled kernels", ["vistrack.kernels"], "The numba kernels the model families share."),
    "system": ("The process", ["vistrack.system"], "Memory and disk budgets, signals, the compile notice."),
}


def modules(package):
    """The public modules of ``package`` (itself first), not those of the packages under it that have a
    page of their own."""
    own = {p for _, pkgs, _ in PAGES.values() for p in pkgs if p.startswith(package + ".")}
    base = ROOT / Path(*package.split("."))
    out = [package]
    for p in sorted(base.rglob("*.py")):
        parts = p.relative_to(ROOT).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        if name == package or any(part.startswith("_") for part in name.split(".")):
            continue
        if any(name == o or name.startswith(o + ".") for o in own):
            continue
        out.append(name)
    return out


def defines(name):
    """Whether module ``name`` defines functions or classes of its own (a package's ``__init__`` that only
    gathers its modules' names is shown by its docstring alone: they are documented where they are)."""
    path = ROOT / Path(*name.split("."))
    path = path / "__init__.py" if path.is_dir() else path.with_suffix(".py")
    return any(isinstance(n, (ast.FunctionDef, ast.ClassDef)) for n in ast.parse(path.read_text()).body)


def page(title, packages, about):
    """The page's markdown."""
    lines = [f"# {title}", "", about, ""]
    for package in packages:
        for name in modules(package):
            lines += [f"::: {name}"] + ([] if defines(name) else ["    options:", "      members: false"]) + [""]
    return "\n".join(lines)


def index():
    rows = [f"| [{title}]({name}.md) | " + ", ".join(f"`{p}`" for p in pkgs) + " |"
            for name, (title, pkgs, _) in PAGES.items()]
    return "\n".join(["# API reference", "",
                      "Generated by mkdocstrings from the numpydoc docstrings of every public module, a page per "
                      "package in the order of the layers (each imports only those below it: "
                      "[Architecture](../architecture.md)); array shapes are given as `(N, d)` for `N` particles "
                      "of dimension `d`, and each docstring cites the seed section it implements (thesis 001, "
                      "PF-EIS paper 000).", "", "| page | packages |", "|---|---|", *rows, ""])


def main():
    API.mkdir(parents=True, exist_ok=True)
    for old in API.glob("*.md"):
        old.unlink()
    for name, spec in PAGES.items():
        (API / f"{name}.md").write_text(page(*spec))
    (API / "index.md").write_text(index())
    print(f"wrote {len(PAGES) + 1} pages into {API.relative_to(ROOT)}")


if __name__ == "__main__":
    sys.exit(main())
