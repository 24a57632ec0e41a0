"""Plots for experiment reports (PNG files).

Figures are :class:`matplotlib.figure.Figure` objects saved directly, without pyplot: importing
this module leaves the user's matplotlib backend alone and opens no window.
"""

from __future__ import annotations

from matplotlib.figure import Figure

from ..io.outputs import replacing


def _subplots():
    fig = Figure(figsize=(6.4, 4.2), dpi=110)
    return fig, fig.add_subplot()


def _finish(fig, ax, path):
    """Grid, legend, layout, save as PNG, close; returns ``path``."""
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, path)


def _save(fig, path):
    """Save ``fig`` as a PNG at ``path``, whole or not at all (:func:`~vistrack.io.outputs.replacing`)."""
    with replacing(path, "plot") as tmp:
        fig.savefig(tmp, format="png")
    return path


__all__ = ["plot_error_vs_time", "plot_error_vs_n", "plot_per_frame", "plot_vs_n", "plot_success", "plot_precision"]


def plot_error_vs_time(curves, path, *, title="Tracking error vs time step", ylabel="mean position error"):
    """One line per (algorithm, N): mean error at each time step (thesis Fig. 4.18, seed 000 Fig. 2)."""
    fig, ax = _subplots()
    for (algo, n), err in curves.items():
        ax.plot(range(1, len(err) + 1), err, marker="o", ms=3, label=f"{algo}, N={n}")
    ax.set_xlabel("time step")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    return _finish(fig, ax, path)


def plot_error_vs_n(results, path, *, key="mean_error_final", err_key="std_error_final",
                    title="Final-step error vs number of particles"):
    """Mean final error ± std vs N, one line per algorithm (thesis Fig. 4.21)."""
    fig, ax = _subplots()
    algos = list(dict.fromkeys(r["algo"] for r in results))
    for algo in algos:
        rows = sorted((r for r in results if r["algo"] == algo), key=lambda r: r["particles"])
        ax.errorbar([r["particles"] for r in rows], [r[key] for r in rows],
                    yerr=[r[err_key] for r in rows], marker="o", capsize=3, label=algo)
    ax.set_xscale("log")
    ax.set_xlabel("number of particles N")
    ax.set_ylabel("mean final-step position error (± std)")
    ax.set_title(title)
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    fig.tight_layout()
    return _save(fig, path)


def plot_per_frame(curves, path, *, ylabel, title, xlabel="frame"):
    """One line per label: a per-frame curve (thesis Figs. 3.9–3.10, 4.15–4.16); ``curves`` maps a
    label to ``y`` or to ``(x, y)`` (a normalised time axis)."""
    fig, ax = _subplots()
    for label, y in curves.items():
        x, y = y if isinstance(y, tuple) else (range(len(y)), y)
        ax.plot(x, y, lw=1.2, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    return _finish(fig, ax, path)


def plot_vs_n(summaries, path, *, key, ylabel, title=None):
    """``key`` (averaged over clips) vs number of particles, one line per algorithm; trackers without
    particles (``particle_filter`` false: OpenCV's, result files) are a dashed level, not a point at N = 1."""
    import numpy as np

    fig, ax = _subplots()
    for i, algo in enumerate(dict.fromkeys(s["algo"] for s in summaries)):
        rows = [s for s in summaries if s["algo"] == algo]
        if not rows[0].get("particle_filter", True):
            v = [s[key] for s in rows if s[key] is not None]
            if v:
                ax.axhline(np.mean(v), ls="--", lw=1.2, color=f"C{i % 10}", label=f"{algo} (no particles)")
            continue
        ns = sorted({s["particles"] for s in rows})
        ys = []
        for n in ns:
            v = [s[key] for s in rows if s["particles"] == n and s[key] is not None]
            ys.append(np.mean(v) if v else np.nan)
        ax.plot(ns, ys, marker="o", color=f"C{i % 10}", label=algo)
    ax.set_xscale("log")
    ax.set_xlabel("number of particles N")
    ax.set_ylabel(ylabel)
    ax.set_title(title or f"{ylabel} vs N")
    return _finish(fig, ax, path)


def plot_success(curves, path, *, title="Success plot (IoU)"):
    """Fraction of frames with IoU above each threshold, with the AUC in the legend."""
    import numpy as np

    fig, ax = _subplots()
    for label, y in curves.items():
        th = np.linspace(0, 1, len(y))
        ax.plot(th, y, label=f"{label} (AUC {np.mean(y):.3f})")
    ax.set_xlabel("IoU threshold")
    ax.set_ylabel("success rate")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.02)
    ax.set_title(title)
    return _finish(fig, ax, path)


def plot_precision(curves, path, *, title="Precision plot (centre error)"):
    """Fraction of frames with the centre error within each threshold (0..50 px, OTB), with the
    precision at 20 px in the legend."""
    import numpy as np

    fig, ax = _subplots()
    for label, y in curves.items():
        th = np.arange(len(y))
        ax.plot(th, y, label=f"{label} (@20 px {y[min(20, len(y) - 1)]:.3f})")
    ax.set_xlabel("centre error threshold (px)")
    ax.set_ylabel("precision")
    ax.set_xlim(0, len(next(iter(curves.values()), [0])) - 1 or 1)
    ax.set_ylim(0, 1.02)
    ax.set_title(title)
    return _finish(fig, ax, path)
