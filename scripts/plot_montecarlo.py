#!/usr/bin/python3
"""Figures of a `cablecal montecarlo` study (the paper's Figs. 6-11, extended), written into
the study folder:
  sigma_vs_n.png       sigma of each identified variable against n, per design (Fig. 6)
  sigma_vs_n.png       also: the failed trials of each design at each n, in a panel below
  distributions.png    error distributions at up to four n of the study (6, 10, 20, 50 when
                       run), random sets if it has them (Figs. 7-9); the axis clipped to
                       robust quantiles, what falls beyond it said in each panel
  one_calibration.png  every variable's error in one calibration at the largest n (Fig. 11):
                       the trial of median error (max |error| over the variables), not trial 1
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


def read_errors(path, keep, cell=None):
    """{(n, design, parameter): [errors in mm]} for parameters in `keep`, and every trial of
    the (n, design) `cell`: {trial: {parameter: error in mm}}."""
    errors = collections.defaultdict(list)
    trials = collections.defaultdict(dict)
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            key = (int(row["n"]), row["design"])
            e = 1e3 * float(row["error"])
            if row["parameter"] in keep:
                errors[key + (row["parameter"],)].append(e)
            if key == cell:
                trials[int(row["trial"])][row["parameter"]] = e
    return errors, trials


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
    """The geometric parameters among `names` in the study's order: a1x (a1y) a1z ... amz, l10 ... lm0
    (a planar robot's exits have x and z, a spatial robot's x, y and z)."""
    seen = [p for p in dict.fromkeys(names) if re.fullmatch(r"a[0-9]+[xyz]|l[0-9]+0", p)]
    return sorted(seen, key=lambda p: (p[0] == "l", int(p[1:-1]), p[-1]))


def held_names(summary):
    """The parameters the gauge held: exactly 0 in every trial of every cell (max_abs 0 wherever
    a cell has successful trials). A planar study's default gauge holds a1x; a spatial study holds
    the coordinates its run.yaml lists under gauge_held."""
    seen = {}
    for r in summary:
        if r["max_abs"] in ("", "nan"):
            continue
        seen[r["parameter"]] = seen.get(r["parameter"], True) and float(r["max_abs"]) == 0.0
    return {p for p, zero in seen.items() if zero}


def held_label(held):
    """The legend's words for the held parameters (the planar default's words kept as they were)."""
    if held == ["a1x"]:
        return "geometric parameters (under the default gauge a1x is held: error 0)"
    if held:
        return "geometric parameters (held by the gauge, error 0: " + ", ".join(held) + ")"
    return "geometric parameters"


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


def sigma_vs_n(summary, out, geometry_sigma_m=None, trials=None):
    # Every geometric parameter but those the gauge held (always 0: a1x under the planar default
    # gauge), then x4; three panels a row (2 x 3 for two cables), and below them a panel of the
    # failed trials: sigma is over the successful trials only, so a design is judged by both.
    held = held_names(summary)
    params = [p for p in geometry_names(r["parameter"] for r in summary) if p not in held] + ["x4"]
    rows_of_panels = (len(params) + 2) // 3
    fig = plt.figure(figsize=(13, 3.5 * rows_of_panels + 2.8))
    grid = fig.add_gridspec(rows_of_panels + 1, 3, height_ratios=[1.0] * rows_of_panels + [0.8])
    axes = np.empty((rows_of_panels, 3), dtype=object)
    for i in range(rows_of_panels):
        for j in range(3):
            axes[i, j] = fig.add_subplot(grid[i, j], sharex=axes[0, 0] if (i or j) else None)
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
        ax.tick_params(labelbottom=True)
    for ax in axes.flat[len(params):]:
        ax.set_visible(False)
    axes.flat[0].legend(fontsize=8)
    # Failed trials per design and n (every parameter's row of a cell has the cell's count).
    ax = fig.add_subplot(grid[rows_of_panels, :], sharex=axes[0, 0])
    failed = {}
    for r in summary:
        if r["failures"] not in ("", None):
            failed[(r["design"], int(r["n"]))] = int(r["failures"])
    offsets = np.linspace(-0.3, 0.3, len(designs)) if len(designs) > 1 else [0.0]
    top = max(failed.values(), default=0)
    for d, dx in zip(designs, offsets):
        cells = sorted((n, f) for (dd, n), f in failed.items() if dd == d)
        if not cells:
            continue
        label, colour = DESIGN_STYLE.get(d, (d, None))
        ax.plot([n for n, _ in cells], [f for _, f in cells], "o-", ms=3, lw=1.0, color=colour, label=label)
        for n, f in cells:
            if f > 0:  # the count written at each n where any trial of this design failed
                ax.annotate(str(f), (n + dx, f), textcoords="offset points", xytext=(0, 4), ha="center",
                            fontsize=6.5, color=colour)
    ax.set_ylim(-0.05 * max(top, 1), 1.25 * max(top, 1))
    of = f" of {int(trials)}" if trials else ""
    ax.set_ylabel(f"failed trials{of}")
    ax.set_title("Failed trials (no verified design, sampling, a pose the true robot cannot hold, or no convergence): "
                 "sigma above is over the others", fontsize=9)
    ax.set_xlabel("number of poses n")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(alpha=0.3)
    fig.suptitle("Standard deviation of the identification error against the number of poses")
    # Past three rows (a spatial robot's exits) the layout would set the first row's titles under
    # the suptitle: leave it 0.45 in. (The planar studies' figures are laid out as before.)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.45 / fig.get_figheight()) if rows_of_panels > 3 else None)
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
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.6))
    for ax, p in zip(axes, params):
        cells = [(n, np.asarray(errors.get((n, design, p), []))) for n in ns]
        cells = [(n, e) for n, e in cells if len(e) >= 2]
        if not cells:
            continue
        # The axis spans the central 98 % of the errors of every n but the smallest (at least
        # +-5 mm): the smallest n's errors (n = 6: random sets spread ten times wider, with tails
        # of metres) would squash every other histogram to a spike. What falls beyond is said
        # in the panel; the legend's sigma counts every trial.
        spread = cells[1:] if len(cells) > 1 else cells
        lim = max(5.0, max(np.percentile(np.abs(e), 98.0) for _, e in spread))
        beyond = []
        for n, e in cells:
            # Bins over this n's own spread (within the axis), each reading weighted so that the
            # area over the axis is the share of trials within it.
            own = min(lim, max(1.0, np.percentile(np.abs(e), 99.5)))
            bins = int(np.clip(len(e) // 5, 8, 60))
            weights = np.full(len(e), bins / (2.0 * own * len(e)))
            ax.hist(e, bins=bins, range=(-own, own), weights=weights, histtype="step", lw=1.4,
                    label=f"n = {n}, sigma = {np.std(e, ddof=1):.2f} mm")
            out_of_axis = np.abs(e) > lim
            if out_of_axis.any():
                beyond.append(f"n = {n}: {out_of_axis.sum()} of {len(e)} trials beyond ±{lim:.3g} mm "
                              f"(max |error| {np.max(np.abs(e)):.3g} mm)")
        ax.set_xlim(-lim, lim)
        ax.set_title(f"{p}, {DESIGN_STYLE.get(design, (design,))[0]}")
        ax.set_xlabel("error (mm)")
        ax.set_ylabel("probability density")
        ax.legend(fontsize=7.5, loc="center right")
        basis = f"n ≥ {spread[0][0]}" if len(cells) > 1 else f"n = {cells[0][0]}"
        ax.text(0.02, 0.98, f"axis: the central 98 % of the errors at {basis}"
                + ("".join("\n" + b for b in beyond) or "\n(no trial beyond it)"),
                transform=ax.transAxes, va="top", ha="left", fontsize=6.5, color="0.25",
                bbox=dict(facecolor="white", edgecolor="none", alpha=0.8, pad=1.0))
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def calibration_cell(summary):
    """The (n, design) whose calibration one_calibration shows: the largest n of random sets
    (the paper's Fig. 11), or of the study's first design."""
    cells = {(int(r["n"]), r["design"]) for r in summary}
    if not cells:
        return None
    return max((c for c in cells if c[1] == "random"), default=None) or max(cells)


def one_calibration(trials, cell, out):
    """A typical calibration: of the cell's successful trials, the one whose largest |error|
    over every identified variable is the median (the lower one of an even count)."""
    if not trials:
        return
    size = {t: np.max(np.abs(list(row.values()))) for t, row in trials.items()}
    ranked = sorted(size, key=lambda t: (size[t], t))
    trial = ranked[(len(ranked) - 1) // 2]
    row = trials[trial]
    names = geometry_names(row)
    geometry_count = len(names)
    held = [p for p in names if row[p] == 0.0]  # a held parameter's error is exactly 0
    names += sorted((p for p in row if p.startswith("x")), key=lambda s: int(s[1:]))
    values = [row[p] for p in names]
    within = 100.0 * np.mean(np.abs(values) <= 5.0)
    fig, ax = plt.subplots(figsize=(13, 4))
    ax.bar(range(len(names)), values,
           color=["tab:red"] * geometry_count + ["tab:blue"] * (len(names) - geometry_count))
    ax.axhline(5, color="0.5", ls="--", lw=0.8)
    ax.axhline(-5, color="0.5", ls="--", lw=0.8)
    ax.legend(handles=[Patch(color="tab:red", label=held_label(held)),
                       Patch(color="tab:blue", label="x of each pose"),
                       Line2D([], [], color="0.5", ls="--", lw=0.8, label="±5 mm")], fontsize=8, loc="upper right")
    ax.set_xticks(range(len(names)))
    ax.set_xticklabels(names, rotation=90, fontsize=7)
    ax.set_ylabel("error (mm)")
    worst = max(size.values())
    ax.set_title(f"All identified variables in one calibration (n = {cell[0]}, {cell[1]} poses, trial {trial}: the median "
                 f"of {len(size)} successful trials by max |error|): max |error| {size[trial]:.2f} mm "
                 f"(worst trial {worst:.2f} mm), {within:.1f} % within ±5 mm", fontsize=9)
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
    cell = calibration_cell(summary)
    errors, trials = read_errors(os.path.join(args.study, "errors.csv"), {"a2x", "l10", "x4"}, cell)
    sigma_vs_n(summary, os.path.join(args.study, "sigma_vs_n.png"), run_setting(args.study, "geometry_sigma_m"),
               run_setting(args.study, "trials"))
    distributions(errors, os.path.join(args.study, "distributions.png"))
    one_calibration(trials, cell, os.path.join(args.study, "one_calibration.png"))
    if args.ablation:
        ablation(args.ablation, os.path.join(args.ablation, "ablation.png"))
    return 0


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # Ctrl-C stops it quietly: cablecal reports it
    sys.exit(main())
