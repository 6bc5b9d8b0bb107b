#!/usr/bin/python3
"""Figures of a spatial robot's calibration report (`cablecal identify --report DIR` on a
`kind: spatial` robot file), drawn from the data files the report writes into DIR:
  exits.png      the exit points, nominal and identified, seen from above (x-y) and from the side
                 (x-z), the identified - nominal change and the 1-sigma ellipses of the covariance
                 magnified by one factor, said in the title (exits.csv)
  residuals.png  every reading's whitened residual per sensor and pose, as the planar report's
                 (residuals.csv; scripts/plot_report.py draws it)
Usage: /usr/bin/python3 scripts/plot_spatial_report.py DIR [--title ROBOT] --frame-min X,Y,Z --frame-max X,Y,Z
           [--home X,Y,Z]
"""
import argparse
import math
import os
import signal
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plot_report  # noqa: E402  (exits with status 3 itself when matplotlib or numpy is missing)

plt = plot_report.plt
np = plot_report.np


def triple(text):
    values = [float(v) for v in text.split(",")]
    if len(values) != 3:
        raise argparse.ArgumentTypeError(f"expected X,Y,Z, got {text!r}")
    return np.array(values)


def ellipse(ax, centre, cov, scale, colour):
    """The 1-sigma ellipse of a 2 x 2 covariance, magnified by `scale`, around `centre`."""
    values, vectors = np.linalg.eigh(cov)
    values = np.clip(values, 0.0, None)
    t = np.linspace(0.0, 2.0 * math.pi, 60)
    circle = np.stack([np.cos(t), np.sin(t)])
    points = vectors @ (np.sqrt(values)[:, None] * circle) * scale
    ax.plot(centre[0] + points[0], centre[1] + points[1], color=colour, lw=1.0)


def exits(folder, title, frame_min, frame_max, home):
    rows = plot_report.read_csv(os.path.join(folder, "exits.csv"))
    n = np.array([[float(r[f"nominal_{c}_m"]) for c in "xyz"] for r in rows])
    a = np.array([[float(r[f"{c}_m"]) for c in "xyz"] for r in rows])
    has_cov = all(r["cov_xx"] != "" for r in rows)
    cov = []
    for r in rows:
        c = np.zeros((3, 3))
        if has_cov:
            keys = {"xx": (0, 0), "xy": (0, 1), "xz": (0, 2), "yy": (1, 1), "yz": (1, 2), "zz": (2, 2)}
            for key, (i, j) in keys.items():
                c[i, j] = c[j, i] = float(r[f"cov_{key}"])
        cov.append(c)
    held = [int(r["held"]) for r in rows]
    # One magnification for changes and ellipses: the largest of them about 4 % of the frame.
    side = float(np.max(frame_max - frame_min))
    largest = max([float(np.max(np.abs(a - n)))] + [3.0 * math.sqrt(max(np.max(np.diag(c)), 0.0)) for c in cov] + [1e-12])
    scale = 10.0 ** math.floor(math.log10(max(1.0, 0.04 * side / largest)))
    fig, axes = plt.subplots(1, 2, figsize=(13, 6))
    for ax, (i, j), name in zip(axes, ((0, 1), (0, 2)), ("top view (x-y)", "side view (x-z)")):
        lo, hi = frame_min[[i, j]], frame_max[[i, j]]
        ax.add_patch(plt.Rectangle(lo, *(hi - lo), fill=False, color="0.5", lw=1.0, ls="--"))
        if home is not None:
            ax.plot(home[i], home[j], "k+", ms=10, label="home")
        for k in range(len(rows)):
            shown = n[k, [i, j]] + scale * (a[k, [i, j]] - n[k, [i, j]])
            ax.plot(*n[k, [i, j]], "o", mfc="none", mec="0.4", ms=8, label="nominal" if k == 0 else None)
            ax.plot(*shown, "o", color="tab:blue" if held[k] == 0 else "tab:orange", ms=4,
                    label=("identified" if k == 0 else None))
            ax.plot([n[k, i], shown[0]], [n[k, j], shown[1]], color="tab:blue", lw=0.8)
            if has_cov:
                ellipse(ax, shown, cov[k][np.ix_([i, j], [i, j])], scale, "tab:red")
            ax.annotate(str(k + 1), n[k, [i, j]], textcoords="offset points", xytext=(6, 4), fontsize=8)
        ax.set_xlabel("xyz"[i] + " (m)")
        ax.set_ylabel("xyz"[j] + " (m)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(name, fontsize=10)
        ax.grid(alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    handles.append(plt.Line2D([], [], color="tab:red", lw=1.0))
    labels.append("1-σ ellipse" if has_cov else "no covariance")
    if any(held):
        handles.append(plt.Line2D([], [], color="tab:orange", marker="o", ls="none", ms=4))
        labels.append("an exit with held coordinates (the gauge)")
    axes[1].legend(handles, labels, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    fig.suptitle(f"{title}: exit points, identified − nominal and σ ellipses magnified ×{scale:g}", fontsize=10)
    plot_report.save(fig, folder, "exits.png")


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("folder")
    ap.add_argument("--title", default="calibration")
    ap.add_argument("--frame-min", type=triple, required=True)
    ap.add_argument("--frame-max", type=triple, required=True)
    ap.add_argument("--home", type=triple)
    args = ap.parse_args()
    title = (args.title if len(args.title) <= 40 else args.title[:39] + "…").replace("$", r"\$")
    if os.path.exists(os.path.join(args.folder, "exits.csv")):
        exits(args.folder, title, args.frame_min, args.frame_max, args.home)
    if os.path.exists(os.path.join(args.folder, "residuals.csv")):
        plot_report.residuals(args.folder, title, True)
    return 0


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    sys.exit(main())
