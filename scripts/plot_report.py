#!/usr/bin/python3
"""Figures of a calibration report (`cablecal identify --report DIR`), drawn from the data files
the report writes into DIR and written beside them:
  estimates.png        identified - nominal per parameter, mm, with +-1 and +-3 sigma (parameters.csv)
  correlation.png      the parameters' correlation matrix, -1 to 1 (correlation.csv, parameters.csv)
  residuals.png        every reading's whitened residual per sensor and pose, the +-4.5 sigma refusal
                       line, down-weighted readings marked (residuals.csv)
  singular_values.png  the identifiability singular values, log scale (singular_values.csv)
  validation.png       held-out poses: predicted - measured z and theta, calibrated and nominal
                       robots, against the sensors' noise (validation.csv; only when the report has it)
Each figure is drawn when its file is in DIR.
Usage: /usr/bin/python3 scripts/plot_report.py DIR [--title ROBOT_NAME] [--whitened] [--condition-number K]
           [--laser-sigma M --inclinometer-sigma RAD]
"""
import argparse
import csv
import math
import os
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
from matplotlib.ticker import FixedLocator, FuncFormatter  # noqa: E402
import numpy as np  # noqa: E402

# The fit is refused beyond this many sigma without a robust loss (identify/identify.h, kOutlierSigmas).
REFUSAL_SIGMAS = 4.5
DPI = 110



def save(fig, folder, name):
    """Lays the figure out, writes it as folder/name and frees it."""
    fig.tight_layout()
    fig.savefig(os.path.join(folder, name), dpi=DPI)
    plt.close(fig)

def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def number(text):
    return float(text) if text not in ("", None) else math.nan


def pose_axis(ax, pose_ids):
    """Poses in the order of their first reading, one x slot each, labelled by pose id: at most
    about 25 labels, so that 200 poses stay legible."""
    step = max(1, math.ceil(len(pose_ids) / 25))
    ticks = list(range(0, len(pose_ids), step))
    ax.xaxis.set_major_locator(FixedLocator(ticks))
    labels = [str(pose_ids[k]) for k in ticks]
    ax.set_xticklabels(labels, fontsize=8, rotation=90 if sum(len(t) + 2 for t in labels) > 80 else 0)
    ax.set_xlim(-0.7, len(pose_ids) - 0.3)


def estimates(folder, title):
    rows = read_csv(os.path.join(folder, "parameters.csv"))
    n = len(rows)
    height = max(3.2, 1.3 + 0.3 * n)
    fig, ax = plt.subplots(figsize=(8.5, height))
    y = np.arange(n)[::-1]  # the first parameter at the top, as in the table
    for yk, r in zip(y, rows):
        change = 1e3 * number(r["change_m"])
        std = 1e3 * number(r["std_m"])
        if r["held"] == "1":
            ax.plot(change, yk, marker="x", color="0.5", ms=7, ls="none")
            ax.annotate("held", (change, yk), textcoords="offset points", xytext=(8, 0), va="center", fontsize=8,
                        color="0.4")
            continue
        if std > 0:
            ax.errorbar(change, yk, xerr=3 * std, color="tab:blue", lw=1.0, capsize=3, alpha=0.6)
            ax.errorbar(change, yk, xerr=std, color="tab:blue", lw=3.0, capsize=0)
        ax.plot(change, yk, "o", color="tab:red" if std > 0 and abs(change) > 3 * std else "tab:blue", ms=5)
        sigmas = number(r["change_sigmas"])
        if not math.isnan(sigmas):
            # The size in sigma at the right margin, where it never overlaps a bar.
            ax.annotate(f"{sigmas:+.1f} σ", (1.01, yk), xycoords=("axes fraction", "data"), va="center", fontsize=8)
    ax.axvline(0.0, color="black", lw=0.8)
    ax.set_yticks(y)
    ax.set_yticklabels([r["parameter"] for r in rows], fontsize=9)
    ax.set_ylim(-0.7, n - 0.3)
    ax.set_xlabel("identified − nominal (mm)")
    ax.grid(axis="x", alpha=0.3)
    fig.legend(handles=[Line2D([], [], color="tab:blue", lw=3, label="±1 σ"),
                        Line2D([], [], color="tab:blue", lw=1, alpha=0.6, label="±3 σ"),
                        Line2D([], [], color="tab:red", marker="o", ls="none", label="beyond 3 σ from nominal")],
               fontsize=8, loc="lower center", ncol=3, frameon=False)
    ax.set_title(f"{title}: change from nominal (right: in σ)", fontsize=10)
    fig.tight_layout(rect=(0, 0.35 / height, 1, 1))  # the legend's strip at the bottom
    fig.savefig(os.path.join(folder, "estimates.png"), dpi=DPI)
    plt.close(fig)


def correlation(folder, title):
    held = {r["parameter"] for r in read_csv(os.path.join(folder, "parameters.csv")) if r["held"] == "1"}
    rows = read_csv(os.path.join(folder, "correlation.csv"))
    names = [r["parameter"] for r in rows if r["parameter"] not in held]
    c = np.array([[number(r[b]) for b in names] for r in rows if r["parameter"] in names])
    n = len(names)
    side = float(np.clip(2.8 + 0.36 * n, 5.0, 11.0))
    fig, ax = plt.subplots(figsize=(side + 1.2, side))
    image = ax.imshow(c, cmap="RdBu_r", vmin=-1.0, vmax=1.0)
    bar = fig.colorbar(image, ax=ax, fraction=0.046, pad=0.04, ticks=[-1, -0.5, 0, 0.5, 1])
    bar.set_label("correlation")
    ax.set_xticks(range(n))
    ax.set_yticks(range(n))
    ax.set_xticklabels(names, rotation=90 if n > 8 else 0, fontsize=9)
    ax.set_yticklabels(names, fontsize=9)
    if n <= 12:
        # Values in the cells while they fit; beyond that the colours and correlation.csv say it.
        for a in range(n):
            for b in range(n):
                ax.text(b, a, f"{c[a, b]:.2f}", ha="center", va="center", fontsize=7,
                        color="white" if abs(c[a, b]) > 0.6 else "black")
    note = f" ({', '.join(sorted(held))} held: not shown)" if held else ""
    ax.set_title(f"{title}: correlation of the identified parameters{note}", fontsize=10)
    save(fig, folder, "correlation.png")


def residuals(folder, title, whitened):
    rows = read_csv(os.path.join(folder, "residuals.csv"))
    pose_ids = list(dict.fromkeys(int(r["pose"]) for r in rows))
    slot = {p: k for k, p in enumerate(pose_ids)}
    encoders = sorted({r["sensor"] for r in rows if r["sensor"].startswith("encoder")}, key=lambda s: int(s[7:]))
    # One panel per sensor besides the encoders: a planar report's laser and inclinometer, a
    # spatial report's "inclinometer roll", "position px", ... grouped by their first word.
    others = list(dict.fromkeys(r["sensor"] for r in rows if not r["sensor"].startswith("encoder")))
    groups = list(dict.fromkeys(s.split(" ")[0] for s in others))
    groups.sort(key=lambda g: ("laser", "inclinometer").index(g) if g in ("laser", "inclinometer") else 2)
    panels = [("encoders", encoders)] + [(g, [s for s in others if s.split(" ")[0] == g]) for g in groups]
    values = np.array([number(r["residual_sigmas"]) for r in rows])
    down = np.array([r["down_weighted"] == "1" for r in rows])
    # The axis spans the readings the fit kept in full; a down-weighted reading far beyond is
    # drawn at the edge, with its value written beside it.
    kept = np.abs(values[~down]) if (~down).any() else np.array([0.0])
    limit = max(6.0, 1.15 * float(kept.max()))
    n = len(pose_ids)
    width = float(np.clip(6.0 + 0.06 * n, 9.0, 16.0))
    fig, axes = plt.subplots(len(panels), 1, figsize=(width, 1.2 + 2.6 * len(panels)), sharex=True, squeeze=False)
    colours = plt.get_cmap("tab10")
    size = float(np.clip(30.0 - 0.12 * n, 7.0, 26.0))
    for ax, (label, sensors) in zip(axes[:, 0], panels):
        dodge = min(0.7 / max(1, len(sensors)), 0.15)
        handles = []
        for i, sensor in enumerate(sensors):
            colour = (colours(i % 10) if label == "encoders" or len(sensors) > 1
                      else ("tab:olive" if sensor.startswith("laser") else "tab:cyan"))
            offset = (i - (len(sensors) - 1) / 2) * dodge
            picked = [(slot[int(r["pose"])] + offset, number(r["residual_sigmas"]), r["down_weighted"] == "1", r)
                      for r in rows if r["sensor"] == sensor]
            xs = np.array([p[0] for p in picked])
            ys = np.array([p[1] for p in picked])
            clipped = np.clip(ys, -limit, limit)
            inside = np.abs(ys) <= limit
            ax.scatter(xs[inside], ys[inside], s=size, color=colour, zorder=3, lw=0)
            # Beyond the axis: a triangle at the edge, pointing the way the value lies.
            for beyond, marker in ((~inside & (ys > 0), "^"), (~inside & (ys < 0), "v")):
                ax.scatter(xs[beyond], clipped[beyond], s=size * 1.6, color=colour, zorder=3, marker=marker, lw=0)
            for x, v, is_down, r in picked:
                if is_down:
                    ax.scatter([x], [np.clip(v, -limit, limit)], s=size * 4, facecolors="none", edgecolors="tab:red",
                               lw=1.4, zorder=4)
                if abs(v) > limit:
                    ax.annotate(f"pose {r['pose']}: {v:.3g} σ", (x, np.sign(v) * limit), textcoords="offset points",
                                xytext=(6, -10 if v > 0 else 4), fontsize=7, color="tab:red")
            handles.append(Line2D([], [], color=colour, marker="o", ls="none",
                                  label=sensor.replace("encoder", "encoder ")))
        for s in (-REFUSAL_SIGMAS, REFUSAL_SIGMAS):
            ax.axhline(s, color="tab:red", ls="--", lw=1.0, zorder=2)
        ax.axhline(0.0, color="0.3", lw=0.6, zorder=1)
        ax.axhspan(-1.0, 1.0, color="0.92", zorder=0)
        ax.set_ylim(-limit * 1.05, limit * 1.05)
        ax.set_ylabel(f"{label}\nresidual (σ)", fontsize=9)
        ax.grid(axis="y", alpha=0.3)
        handles.append(Line2D([], [], color="tab:red", ls="--", lw=1.0,
                              label=f"±{REFUSAL_SIGMAS:g} σ: refused beyond, without --loss"))
        if any(r["down_weighted"] == "1" for r in rows if r["sensor"] in sensors):
            handles.append(Line2D([], [], marker="o", ls="none", mfc="none", mec="tab:red", ms=9,
                                  label="down-weighted by the loss"))
        ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.005, 1.0), frameon=False)
    pose_axis(axes[-1, 0], pose_ids)
    axes[-1, 0].set_xlabel("pose (in the order of the measurements; several readings of one pose share its place)")
    what = ("each reading's residual, model − reading, over its sensor's σ" if whitened else
            "each cable-length residual over the laser's σ (estimator paper)")
    fig.suptitle(f"{title}: {what} (grey: ±1 σ)", fontsize=10)
    save(fig, folder, "residuals.png")


def short(v):
    """About 3 significant digits, short: 544, 3199, 3.92e5."""
    if 100 <= v < 1e4:
        return f"{v:.0f}"
    if v >= 1e4:
        mantissa, exponent = f"{v:.2e}".split("e")
        return f"{mantissa}e{int(exponent)}"
    return f"{v:.3g}"


def singular_values(folder, title, whitened, condition):
    values = np.array([number(r["singular_value"]) for r in read_csv(os.path.join(folder, "singular_values.csv"))])
    positive = values[values > 0]
    floor = positive.min() / 10 if positive.size else 1.0
    drawn = np.where(values > 0, values, floor)
    k = len(values)
    fig, ax = plt.subplots(figsize=(max(6.0, 3.0 + 0.4 * k), 4.2))
    ax.bar(range(1, k + 1), drawn, color=["tab:blue" if v > 0 else "tab:red" for v in values])
    for x, v, d in zip(range(1, k + 1), values, drawn):
        ax.annotate(short(v), (x, d), textcoords="offset points", xytext=(0, 3), ha="center", fontsize=7,
                    rotation=90 if k > 10 else 0)
    ax.set_yscale("log")
    ax.set_ylim(drawn.min() / 3, drawn.max() * (30 if k > 10 else 5))
    ax.set_xticks(range(1, k + 1))
    ax.set_xlabel("singular value, largest first")
    ax.set_ylabel("singular value (log scale)")
    ax.grid(axis="y", alpha=0.3, which="both")
    if whitened:
        # Whitened by the sensors' sigmas, a singular value s says how well its direction of the
        # parameters is known: one standard deviation of 1/s metres along it.
        right = ax.secondary_yaxis("right", functions=(lambda v: 1e3 / np.maximum(v, 1e-300),
                                                       lambda v: 1e3 / np.maximum(v, 1e-300)))
        right.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        right.set_ylabel("σ along its direction (mm) = 1000 / s")
    ax.set_title(f"{title}: identifiability, condition number {condition}", fontsize=10)
    save(fig, folder, "singular_values.png")


def validation(folder, title, noise):
    rows = read_csv(os.path.join(folder, "validation.csv"))
    robots = [name for name in ("calibrated", "nominal") if f"x_{name}_m" in rows[0]]
    panels = [(sensor, scale, unit) for sensor, scale, unit in (("z", 1e3, "mm"), ("theta", 1e3, "mrad"))
              if f"{sensor}_error_calibrated_{'m' if sensor == 'z' else 'rad'}" in rows[0]]
    pose_ids = list(dict.fromkeys(int(r["pose"]) for r in rows))
    slot = {p: k for k, p in enumerate(pose_ids)}
    n = len(pose_ids)
    fig, axes = plt.subplots(len(panels), 1, figsize=(float(np.clip(6.0 + 0.06 * n, 9.0, 16.0)), 1.2 + 2.8 * len(panels)),
                             sharex=True, squeeze=False)
    style = {"calibrated": ("tab:blue", "o"), "nominal": ("0.55", "s")}
    for ax, (sensor, scale, unit) in zip(axes[:, 0], panels):
        column_unit = "m" if sensor == "z" else "rad"
        for k, name in enumerate(robots):
            errors = np.array([scale * number(r[f"{sensor}_error_{name}_{column_unit}"]) for r in rows])
            xs = np.array([slot[int(r["pose"])] for r in rows]) + (k - (len(robots) - 1) / 2) * 0.2
            rms = float(np.sqrt(np.mean(errors ** 2)))
            colour, marker = style[name]
            ax.scatter(xs, errors, s=22, color=colour, marker=marker, zorder=3,
                       label=f"{name}: rms {rms:.3g} {unit}, max {np.abs(errors).max():.3g} {unit}")
        sigma = noise[sensor]
        if sigma:
            ax.axhspan(-scale * sigma, scale * sigma, color="0.9", zorder=0,
                       label=f"±1 σ of the sensor's noise ({scale * sigma:.3g} {unit})")
        ax.axhline(0.0, color="0.3", lw=0.6)
        ax.set_ylabel(f"{'z' if sensor == 'z' else 'θ'}: predicted − measured ({unit})", fontsize=9)
        ax.grid(axis="y", alpha=0.3)
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.005, 1.0), frameon=False)
    pose_axis(axes[-1, 0], pose_ids)
    axes[-1, 0].set_xlabel("held-out pose")
    fig.suptitle(f"{title}: held-out poses, the forward model's prediction against the laser and inclinometer",
                 fontsize=10)
    save(fig, folder, "validation.png")


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("folder")
    ap.add_argument("--title", default="calibration")
    ap.add_argument("--laser-sigma", type=float, help="m: the held-out z errors are drawn against it")
    ap.add_argument("--inclinometer-sigma", type=float, help="rad: the held-out theta errors are drawn against it")
    ap.add_argument("--whitened", action="store_true",
                    help="estimator ml: the singular values are of the whitened Jacobian (also show 1/s in mm), "
                         "every sensor's residual over its own sigma")
    ap.add_argument("--condition-number", default="n/a", help="as the result says it (inf with a null direction)")
    args = ap.parse_args()
    have = lambda name: os.path.exists(os.path.join(args.folder, name))  # noqa: E731
    # A robot's name, not mathtext; shortened so that it leaves room for what the figure shows.
    title = (args.title if len(args.title) <= 40 else args.title[:39] + "…").replace("$", r"\$")
    if have("parameters.csv"):
        estimates(args.folder, title)
    if have("correlation.csv"):
        correlation(args.folder, title)
    if have("residuals.csv"):
        residuals(args.folder, title, args.whitened)
    if have("singular_values.csv"):
        singular_values(args.folder, title, args.whitened, args.condition_number)
    if have("validation.csv"):
        validation(args.folder, title, {"z": args.laser_sigma, "theta": args.inclinometer_sigma})
    return 0


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # Ctrl-C stops it quietly: cablecal reports it
    sys.exit(main())
