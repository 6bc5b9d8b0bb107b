#!/usr/bin/python3
"""Figures of a spatial robot's calibration report (`cablecal identify --report DIR` on a
`kind: spatial` robot file), drawn from the data files the report writes into DIR:
  exits.png      every exit point seen from above (x-y) and from the side (x-z): identified - nominal
                 in mm, one panel per exit on one scale, with its 1- and 3-sigma ellipses from the
                 covariance (exits.csv)
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


def exits(folder, title, frame_min, frame_max, home):
    """One small panel per exit point and view, centred on its nominal position, in mm: the
    identified point, and its 1- and 3-sigma ellipses (the covariance's 2 x 2 block)."""
    rows = plot_report.read_csv(os.path.join(folder, "exits.csv"))
    m = len(rows)
    n = np.array([[float(r[f"nominal_{c}_m"]) for c in "xyz"] for r in rows])
    a = np.array([[float(r[f"{c}_m"]) for c in "xyz"] for r in rows])
    has_cov = all(r["cov_xx"] != "" for r in rows)
    keys = {"xx": (0, 0), "xy": (0, 1), "xz": (0, 2), "yy": (1, 1), "yz": (1, 2), "zz": (2, 2)}
    cov = []
    for r in rows:
        c = np.zeros((3, 3))
        if has_cov:
            for key, (i, j) in keys.items():
                c[i, j] = c[j, i] = float(r[f"cov_{key}"])
        cov.append(c * 1e6)  # mm^2
    held = [int(r["held"]) for r in rows]
    change = (a - n) * 1e3
    # One scale for every panel, so that the exits compare at a glance.
    reach = max([float(np.max(np.abs(change)))] + [3.2 * math.sqrt(max(float(np.max(np.diag(c))), 0.0)) for c in cov]
                + [1e-3])
    reach *= 1.15
    cols = min(m, 6)
    blocks = math.ceil(m / cols)
    views = (((0, 1), "top view: y vs x"), ((0, 2), "side view: z vs x"))
    fig, axes = plt.subplots(2 * blocks, cols, figsize=(2.3 * cols + 1.5, 2.4 * 2 * blocks + 0.8), squeeze=False)
    for v, ((i, j), name) in enumerate(views):
        for k in range(blocks * cols):
            ax = axes[v * blocks + k // cols, k % cols]
            if k >= m:
                ax.axis("off")
                continue
            ax.axhline(0.0, color="0.8", lw=0.6)
            ax.axvline(0.0, color="0.8", lw=0.6)
            ax.plot(0.0, 0.0, "o", mfc="none", mec="0.4", ms=7)
            ax.plot(change[k, i], change[k, j], "o", ms=4, color="tab:orange" if held[k] else "tab:blue")
            if has_cov:
                block = cov[k][np.ix_([i, j], [i, j])]
                for sigmas, style in ((1.0, "-"), (3.0, ":")):
                    values, vectors = np.linalg.eigh(block)
                    t = np.linspace(0.0, 2.0 * math.pi, 60)
                    pts = vectors @ (np.sqrt(np.clip(values, 0.0, None))[:, None] * np.stack([np.cos(t), np.sin(t)]))
                    ax.plot(change[k, i] + sigmas * pts[0], change[k, j] + sigmas * pts[1], color="tab:red", lw=0.9,
                            ls=style)
            ax.set_xlim(-reach, reach)
            ax.set_ylim(-reach, reach)
            ax.set_aspect("equal")
            ax.tick_params(labelsize=7)
            ax.set_title(f"exit {k + 1}" + (f" ({held[k]} held)" if held[k] else ""), fontsize=8)
            if k % cols == 0:
                ax.set_ylabel(f"{name}\n{'xyz'[j]} − nominal (mm)", fontsize=8)
            ax.set_xlabel(f"{'xyz'[i]} − nominal (mm)", fontsize=7)
    handles = [plt.Line2D([], [], marker="o", ls="none", mfc="none", mec="0.4", ms=7),
               plt.Line2D([], [], marker="o", ls="none", color="tab:blue", ms=4),
               plt.Line2D([], [], color="tab:red", lw=0.9), plt.Line2D([], [], color="tab:red", lw=0.9, ls=":")]
    labels = ["nominal", "identified", "1-σ ellipse", "3-σ ellipse"]
    if any(held):
        handles.append(plt.Line2D([], [], marker="o", ls="none", color="tab:orange", ms=4))
        labels.append("coordinates held (the gauge)")
    fig.legend(handles, labels, fontsize=8, loc="lower center", ncol=len(labels), frameon=False)
    fig.suptitle(f"{title}: exit points, identified − nominal, top and side views" +
                 ("" if has_cov else " (no covariance)"), fontsize=10)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    fig.savefig(os.path.join(folder, "exits.png"), dpi=plot_report.DPI)
    plt.close(fig)


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
