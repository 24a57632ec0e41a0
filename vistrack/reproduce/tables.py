"""What the ``reproduce`` experiments print and plot: one table and one set of figures each.

Each experiment's summaries (``results``: one dict per algorithm and N, as the
experiment modules return them) become a fixed-width text table
(:func:`format_table` with the experiment's columns) and the PNGs of the
thesis's figures (:func:`write_plots`).
"""

from __future__ import annotations

import os

__all__ = ["TABLES", "FIRST_PLOT", "format_table", "write_plots"]

#: per experiment: (header, key, format) of every column; the first column is left-aligned
TABLES = {
    "bearings": [("algo", "algo", "<24"), ("N", "particles", ">6d"), ("ships", "ships", ">5d"),
                 ("final err", "mean_error_final", ">10.5f"), ("± std", "std_error_final", ">9.5f"),
                 ("mean err", "mean_error", ">9.5f"), ("ms/run", "ms_per_run", ">8.2f")],
    "contour": [("algo", "algo", "<10"), ("N", "particles", ">6d"), ("P(lost) final", "p_lost_final", ">13.3f"),
                ("P(lost) mean", "p_lost_mean", ">12.3f"), ("mean err px", "mean_error", ">11.2f"),
                ("ms/frame", "ms_per_frame", ">9.2f"), ("frames/s", "frames_per_s", ">9.0f"),
                ("mean ESS", "mean_ess", ">9.1f")],
    "hs-sir": [("algo", "algo", "<13"), ("N", "particles", ">6d"), ("P(lost) final", "p_lost_final", ">13.3f"),
               ("P(lost) mean", "p_lost_mean", ">12.3f"), ("mean err px", "mean_error", ">11.2f"),
               ("ms/frame", "ms_per_frame", ">9.2f"), ("frames/s", "frames_per_s", ">9.0f"),
               ("mean ESS", "mean_ess", ">9.1f")],
    "landmarks": [("algo", "algo", "<10"), ("N", "particles", ">4d"), ("K", "k", ">2d"),
                  ("mean MSE", "mean_mse", ">9.4f"), ("final MSE", "final_mse", ">10.4f"),
                  ("median run", "median_run_mse", ">10.4f"), ("ms/run", "ms_per_run", ">8.1f")],
    "plates": [("algo", "algo", "<15"), ("N", "particles", ">5d"), ("MOTA", "mota", ">6.3f"),
               ("IDF1", "idf1", ">6.3f"), ("MOTP px", "motp", ">7.2f"), ("switches", "switches_per_run", ">8.2f"),
               ("false pos.", "false_positives_per_run", ">10.1f"), ("misses", "misses_per_run", ">7.1f"),
               ("empty-frame rep.", "empty_frame_reports", ">16d"), ("ms/frame", "ms_per_frame", ">9.2f"),
               ("ESS", "mean_ess", ">6.1f")],
    "plate": [("algo", "algo", "<10"), ("N", "particles", ">5d"), ("P(lost)", "p_lost", ">8.3f"),
              ("vertex err", "mean_vertex_error", ">10.2f"), ("false rep.", "false_reports", ">10d"),
              ("acq<=10", "acquired_within", ">8.2f"), ("never", "never_acquired", ">6d"),
              ("mean acq", "mean_acquisition_delay", ">8.1f"), ("ms/frame", "ms_per_frame", ">9.2f"),
              ("frames/s", "frames_per_s", ">9.0f"), ("ESS", "mean_ess", ">6.1f")],
}


#: per experiment: the file name of its first figure (:func:`write_plots`)
FIRST_PLOT = {"bearings": "error_vs_time.png", "landmarks": "mse_vs_time.png", "contour": "p_lost_vs_frame.png",
              "hs-sir": "p_lost_vs_frame.png", "plate": "p_lost_vs_frame.png", "plates": "p_lost_vs_frame.png"}


def format_table(experiment, results):
    """The text table of ``results`` with the columns of ``TABLES[experiment]`` (the first column
    as wide as its longest entry)."""
    cols = TABLES[experiment]
    widths = [int("".join(c for c in fmt.split(".")[0] if c.isdigit())) for _, _, fmt in cols]
    first = cols[0][1]  # the left-aligned name column widens to the longest name
    widths[0] = max([widths[0]] + [len(str(r[first])) for r in results if r[first] is not None])
    cols = [(cols[0][0], first, f"<{widths[0]}")] + list(cols[1:])
    head = " ".join(format(h, f"{fmt[0]}{w}") for (h, _, fmt), w in zip(cols, widths))
    lines = [head, "-" * len(head)]
    for r in results:
        lines.append(" ".join(format("-", f"{fmt[0]}{w}") if r[key] is None else format(r[key], fmt)
                              for (_, key, fmt), w in zip(cols, widths)))
    return "\n".join(lines)


def write_plots(experiment, out, plots_dir, title=""):
    """The experiment's figures as PNGs in ``plots_dir`` (created); returns their paths.

    ``out`` is ``{"results": [...], "curves": {...}}`` as the experiment modules return it
    (bearings and landmarks plot their curves, contour and plate their per-frame results).
    """
    from ..reports import plots

    os.makedirs(plots_dir, exist_ok=True)

    def path(name):
        return os.path.join(plots_dir, name)

    results = out["results"]
    if experiment == "bearings":
        return [plots.plot_error_vs_time(out["curves"], path("error_vs_time.png"),
                                         title=f"{title}: error vs time (Fig. 4.18)"),
                plots.plot_error_vs_n(results, path("error_vs_n.png"), title=f"{title}: final error vs N (Fig. 4.21)")]
    if experiment == "landmarks":
        return [plots.plot_error_vs_time(out["curves"], path("mse_vs_time.png"), ylabel="MSE of the configuration",
                                         title=f"{title} (Fig. 2)")]
    lab = {f"{r['algo']}, N={r['particles']}": r for r in results}
    if experiment in ("contour", "hs-sir"):
        what = "Contour" if experiment == "contour" else "History sampling"
        return [plots.plot_per_frame({k: r["p_lost_per_frame"] for k, r in lab.items()}, path("p_lost_vs_frame.png"),
                                     ylabel="P(lost)", title=f"{what}: probability of losing the object (Fig. 3.10)"),
                plots.plot_per_frame({k: r["error_per_frame"] for k, r in lab.items()}, path("error_vs_frame.png"),
                                     ylabel="mean centre error (px), runs not lost",
                                     title=f"{what}: tracking error (Fig. 3.9)")]
    curves = {k: [float("nan") if v is None else v for v in r["p_lost_per_frame"]]
              for k, r in lab.items() if r["p_lost_per_frame"] is not None}
    return [plots.plot_per_frame(curves, path("p_lost_vs_frame.png"), ylabel="P(lost), frames with a plate",
                                 title="Plates: probability of losing the plate (Fig. 4.15)")]
