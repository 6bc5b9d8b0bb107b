#!/usr/bin/python3
"""Figures of a `cablecal montecarlo` study (the paper's Figs. 6-11, extended), written into
the study folder:
  sigma_vs_n.png       sigma of each identified variable against n, per design (Fig. 6)
  distributions.png    error distributions at up to four n of the study (6, 10, 20, 50 when
                       run), random sets if it has them (Figs. 7-9)
  one_calibration.png  every variable's error in one calibration at the largest n (Fig. 11)
  ablation.png         with --ablation DIR: a2x errors at n = 50 per noisy-sensor setting (Fig. 10)
Usage: /usr/bin/python3 scripts/plot_montecarlo.py STUDY_DIR [--ablation ABLATION_DIR]
"""
import argparse
import collections
import csv
import os
import re
import signal
import sys

try:
    import matplotlib
    import numpy  # noqa: F401
except ImportError as missing:
    # Exit status 3 tells cablecal that a library is missing, not that the figure failed
    # (cli/commands.cc, kMissingPlotLibraryExit): it then says what to install.
    sys.stderr.write(f"{sys.executable}: {missing}: the figures need matplotlib and numpy\n")
    sys.exit(3)

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.ticker import FuncFormatter, MaxNLocator  # noqa: E402
import numpy as np  # noqa: E402


def read_summary(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def read_errors(path, keep):
    """{(n, design, parameter): [errors in mm]} for parameters in `keep`, and the trial-1 rows."""
    errors = collections.defaultdict(list)
    first_trial = collections.defaultdict(dict)
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            key = (int(row["n"]), row["design"])
            e = 1e3 * float(row["error"])
            if row["parameter"] in keep:
                errors[key + (row["parameter"],)].append(e)
            if row["trial"] == "1":
                first_trial[key][row["parameter"]] = e
    return errors, first_trial


# Full names and fixed colours, so that a design keeps its colour from one figure to the next.
DESIGN_STYLE = {
    "random": ("random sets", "tab:gray"),
    "optimized": ("optimized (A-optimal, the default)", "tab:red"),
    "a": ("A-optimal", "tab:orange"),
    "d": ("D-optimal", "tab:green"),
    "e": ("E-optimal", "tab:purple"),
    "condition": ("condition number (the paper's)", "tab:blue"),
}


def geometry_names(names):
    """The geometric parameters among `names` in the study's order: a1x a1z ... amz, l10 ... lm0."""
    seen = [p for p in dict.fromkeys(names) if re.fullmatch(r"a[0-9]+[xz]|l[0-9]+0", p)]
    return sorted(seen, key=lambda p: (p[0] == "l", int(p[1:-1]), p[-1]))


def run_setting(study, key):
    """A number from the study's run.yaml (`key: value` at the start of a line), or None."""
    try:
        with open(os.path.join(study, "run.yaml")) as f:
            for line in f:
                m = re.match(rf"{key}:\s*([-+0-9.eE]+)\s*$", line)
                if m:
                    return float(m.group(1))
    except OSError:
        pass
    return None


def sigma_vs_n(summary, out, geometry_sigma_m=None):
    # Every geometric parameter but the gauge's a1x (always 0 under gauge a1x), then x4; three
    # panels a row (2 x 3 for two cables).
    params = [p for p in geometry_names(r["parameter"] for r in summary) if p != "a1x"] + ["x4"]
    rows_of_panels = (len(params) + 2) // 3
    fig, axes = plt.subplots(rows_of_panels, 3, figsize=(13, 3.5 * rows_of_panels), sharex=True, squeeze=False)
    order = list(DESIGN_STYLE)
    designs = sorted({r["design"] for r in summary}, key=lambda d: order.index(d) if d in order else len(order))
    for ax, p in zip(axes.flat, params):
        for d in designs:
            # Cells with too few successful trials have no sigma (empty or non-finite): skip them.
            rows = sorted((int(r["n"]), 1e3 * float(r["std"])) for r in summary
                          if r["parameter"] == p and r["design"] == d and r["std"] not in ("", "nan"))
            if rows:
                label, colour = DESIGN_STYLE.get(d, (d, None))
                ax.plot([r[0] for r in rows], [r[1] for r in rows], "o-", ms=3, label=label, color=colour)
        if geometry_sigma_m and p != "x4":
            # Without calibration the nominal geometry is off by the true robots' spread itself.
            ax.axhline(1e3 * geometry_sigma_m, color="black", ls="--", lw=1.0,
                       label=f"nominal, uncalibrated ({1e3 * geometry_sigma_m:g} mm)")
        ax.set_title(p)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        # Log scale: sigma falls by an order of magnitude from n = 6 to 50, and the designs'
        # differences at large n would vanish on a linear axis.
        ax.set_yscale("log")
        # Plain numbers (2, 5, 10, 20 mm), not 2 x 10^0.
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(FuncFormatter(
            lambda v, _: f"{v:g}" if f"{v:.0e}"[0] in "25" else ""))
        ax.set_ylabel("sigma (mm, log scale)")
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(params):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("number of poses n")
    axes.flat[0].legend(fontsize=8)
    fig.suptitle("Standard deviation of the identification error against the number of poses")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def distributions(errors, out):
    params = ["a2x", "l10", "x4"]
    # The study's own n and designs: random sets if it has them, else its first design, at up
    # to four n spread over those it ran (the paper's 6, 10, 20, 50 when they are there).
    order = list(DESIGN_STYLE)
    designs = sorted({k[1] for k in errors}, key=lambda d: order.index(d) if d in order else len(order))
    if not designs:
        return
    design = designs[0]
    run = sorted({k[0] for k in errors if k[1] == design})
    ns = [n for n in (6, 10, 20, 50) if n in run]
    if len(ns) < min(4, len(run)):
        ns = sorted({run[int(round(i))] for i in np.linspace(0, len(run) - 1, min(4, len(run)))})
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    for ax, p in zip(axes, params):
        for n in ns:
            e = errors.get((n, design, p))
            if not e or len(e) < 2:
                continue
            lim = max(5.0, np.percentile(np.abs(e), 99.5))
            # About 5 trials a bin at least: a short study gets a coarser, readable histogram.
            ax.hist(e, bins=int(np.clip(len(e) // 5, 8, 60)), range=(-lim, lim), density=True, histtype="step",
                    lw=1.4, label=f"n = {n}, sigma = {np.std(e, ddof=1):.2f} mm")
        ax.set_title(f"{p}, {DESIGN_STYLE.get(design, (design,))[0]}")
        ax.set_xlabel("error (mm)")
        ax.set_ylabel("probability density")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def one_calibration(first_trial, out):
    if not first_trial:
        return
    key = max((k for k in first_trial if k[1] == "random"), default=None) or max(first_trial)
    row = first_trial[key]
    names = geometry_names(row)
    geometry_count = len(names)
    names += sorted((p for p in row if p.startswith("x")), key=lambda s: int(s[1:]))
    values = [row[p] for p in names]
    within = 100.0 * np.mean(np.abs(values) <= 5.0)
    fig, ax = plt.subplots(figsize=(13, 4))
    ax.bar(range(len(names)), values,
           color=["tab:red"] * geometry_count + ["tab:blue"] * (len(names) - geometry_count))
    ax.axhline(5, color="0.5", ls="--", lw=0.8)
    ax.axhline(-5, color="0.5", ls="--", lw=0.8)
    ax.legend(handles=[Patch(color="tab:red", label="geometric parameters (under the default gauge a1x is held: error 0)"),
                       Patch(color="tab:blue", label="x of each pose"),
                       Line2D([], [], color="0.5", ls="--", lw=0.8, label="±5 mm")], fontsize=8, loc="upper right")
    ax.set_xticks(range(len(names)))
    ax.set_xticklabels(names, rotation=90, fontsize=7)
    ax.set_ylabel("error (mm)")
    ax.set_title(f"All identified variables in one calibration (n = {key[0]}, {key[1]} poses, trial 1): "
                 f"max |error| {np.max(np.abs(values)):.2f} mm, {within:.1f} % within ±5 mm")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def ablation(folder, out):
    settings = ["both", "laser", "inclinometer", "none"]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for s in settings:
        path = os.path.join(folder, s, "errors.csv")
        if not os.path.exists(path):
            continue
        errors, _ = read_errors(path, {"a2x"})
        e = [v for k, vals in errors.items() for v in vals]
        if e:
            ax.hist(e, bins=60, range=(-20, 20), density=True, histtype="step", lw=1.4,
                    label=f"noisy: {s}, sigma = {np.std(e, ddof=1):.3f} mm")
    ax.set_xlabel("a2x error (mm)")
    ax.set_ylabel("probability density")
    ax.set_title("Effect of each sensor's noise on a2x at n = 50 (random pose sets)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("study")
    ap.add_argument("--ablation")
    args = ap.parse_args()
    summary = read_summary(os.path.join(args.study, "summary.csv"))
    errors, first_trial = read_errors(os.path.join(args.study, "errors.csv"), {"a2x", "l10", "x4"})
    sigma_vs_n(summary, os.path.join(args.study, "sigma_vs_n.png"), run_setting(args.study, "geometry_sigma_m"))
    distributions(errors, os.path.join(args.study, "distributions.png"))
    one_calibration(first_trial, os.path.join(args.study, "one_calibration.png"))
    if args.ablation:
        ablation(args.ablation, os.path.join(args.ablation, "ablation.png"))
    return 0


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # Ctrl-C stops it quietly: cablecal reports it
    sys.exit(main())
