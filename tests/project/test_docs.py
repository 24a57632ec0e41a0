"""The manual, the docs site and the linter: README.md is short and its links resolve, the mkdocs
site builds in strict mode (a broken link, anchor or API reference fails it), and ``ruff check``
passes with the configuration in pyproject.toml."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

from path_helpers import ROOT

README = ROOT / "README.md"
MAX_README_LINES = 300

# [text](target) outside code spans; images too
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def _prose(text):
    """``text`` without fenced code blocks and inline code spans (links there are not links)."""
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)
    return re.sub(r"`[^`\n]*`", "", text)


def _slug(heading):
    """GitHub's (and mkdocs' toc) anchor of a heading: lower case, punctuation dropped, spaces to ``-``."""
    s = re.sub(r"`", "", heading.strip().lower())
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def _anchors(path):
    text = re.sub(r"^```.*?^```", "", path.read_text(encoding="utf-8"), flags=re.S | re.M)
    return {_slug(m.group(1)) for m in re.finditer(r"^#{1,6}\s+(.+?)\s*#*\s*$", text, flags=re.M)}


def _relative_links(path):
    for target in LINK.findall(_prose(path.read_text(encoding="utf-8"))):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
            continue
        yield target


def test_slug_follows_github():
    assert _slug("From Python, in the shape of OpenCV's trackers") == "from-python-in-the-shape-of-opencvs-trackers"
    assert _slug("Batch evaluation (`vistrack eval`, on Dask)") == "batch-evaluation-vistrack-eval-on-dask"


def test_readme_is_a_short_manual():
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= MAX_README_LINES, f"README.md has {len(lines)} lines (at most {MAX_README_LINES})"
    text = "\n".join(lines)
    # the two Quick-start commands, verbatim: .ci/run installs and tests exactly as they say
    assert 'pip install . && vistrack demo' in text
    assert 'pip install ".[test]" && pytest -q' in text


def test_readme_relative_links_resolve():
    """Every relative link in README.md names an existing file, and every ``#anchor`` a heading there."""
    links = list(_relative_links(README))
    assert links, "README.md links nothing"
    bad = []
    for target in links:
        file, _, anchor = target.partition("#")
        dest = (README.parent / file).resolve() if file else README
        if not dest.exists():
            bad.append(f"{target}: no file {dest.relative_to(ROOT) if dest.is_relative_to(ROOT) else dest}")
        elif anchor and dest.suffix == ".md" and anchor not in _anchors(dest):
            bad.append(f"{target}: no heading #{anchor} in {dest.name}")
    assert not bad, "README.md: broken links:\n" + "\n".join(bad)


def test_readme_generated_blocks_are_delimited():
    """The tables regenerated from a command sit between ``<!-- BEGIN name: command -->`` and
    ``<!-- END name -->``, each name once, in order."""
    text = README.read_text(encoding="utf-8")
    begins = re.findall(r"<!-- BEGIN ([\w-]+): (.+?) -->", text)
    ends = re.findall(r"<!-- END ([\w-]+) -->", text)
    assert [name for name, _ in begins] == ends
    assert {"demo", "real-clips"} <= set(ends)
    for name, _ in begins:
        block = text.split(f"<!-- BEGIN {name}:")[1].split(f"<!-- END {name} -->")[0]
        assert "\n|---" in block, f"block {name} holds no table"


@pytest.mark.slow
@pytest.mark.skipif(importlib.util.find_spec("mkdocs") is None or importlib.util.find_spec("mkdocstrings") is None,
                    reason="mkdocs / mkdocstrings not installed (pip install '.[test]')")
def test_docs_site_builds_strict(tmp_path):
    """``mkdocs build --strict``: a warning (a broken link or anchor, a missing page, an API
    reference that does not resolve) fails the build."""
    cmd = [sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file", str(ROOT / "mkdocs.yml"),
           "--site-dir", str(tmp_path / "site")]
    res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    assert (tmp_path / "site" / "index.html").is_file()
    api = (tmp_path / "site" / "api" / "filters" / "index.html").read_text(encoding="utf-8")
    assert "make_filter" in api and "ParticleFilter" in api  # the reference is generated from the docstrings


@pytest.mark.skipif(importlib.util.find_spec("ruff") is None, reason="ruff not installed (pip install '.[test]')")
def test_ruff_check_passes():
    res = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", str(ROOT)], cwd=ROOT,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr


def test_the_layering_holds():
    """import-linter's contracts in pyproject.toml: no import circle between vistrack's packages and
    modules, the library never imports the command line, models never import filters or the engine,
    the core imports nothing above it (docs/architecture.md)."""
    pytest.importorskip("importlinter", reason="import-linter is not installed (pip install '.[test]')")
    lint = Path(sys.executable).with_name("lint-imports")
    cmd = [str(lint)] if lint.exists() else [sys.executable, "-c", "from importlinter.cli import "
                                             "lint_imports_command; lint_imports_command()"]
    res = subprocess.run([*cmd, "--no-cache"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-2000:]
    assert "0 broken" in res.stdout


def test_the_api_reference_covers_every_public_module():
    """Every public module of vistrack has its section on an API page (``tools/api_pages.py`` writes
    them), and the experiment log is a file of the repository, not a page of the site."""
    pages = sorted((ROOT / "docs" / "api").glob("*.md"))
    documented = {line[4:].strip() for p in pages for line in p.read_text(encoding="utf-8").splitlines()
                  if line.startswith("::: ")}
    public = set()
    for p in (ROOT / "vistrack").rglob("*.py"):
        parts = p.relative_to(ROOT).with_suffix("").parts
        parts = parts[:-1] if parts[-1] == "__init__" else parts
        if not any(part.startswith("_") for part in parts):
            public.add(".".join(parts))
    assert len(public) > 150 and sorted(public - documented) == [], "run python tools/api_pages.py"
    site = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    assert "experiments.md" not in site.split("nav:")[1] and "  experiments.md" in site.split("nav:")[0]
