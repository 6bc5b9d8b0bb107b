#!/usr/bin/python3
"""Draws a pose plan over the feasible workspace: each pose's bar (anchor to anchor) and its
two cables (straight from the anchor to the exit point: the pulley wrap, a few centimetres,
is not drawn). Called by `cablecal design --plot`; usable alone:
  /usr/bin/python3 scripts/plot_plan.py plan.csv out.png --workspace ws.csv --frame 5.209,2.8 \
      --exit 0,2.8 --anchor -0.25,0 --exit 5.209,2.8 --anchor 0.25,0
"""
import argparse
import csv
import math
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
import numpy as np  # noqa: E402


def pair(text):
    a, b = text.split(",")
    return float(a), float(b)


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def place_labels(fig, ax, labels):
    """One label per place ("pose 3" or "poses 1, 4"), each put at the first of a few offsets
    around its point where it overlaps no label placed before it."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    kept = []
    offsets = [(0, -11), (0, 11), (34, 0), (-34, 0), (0, -22), (0, 22), (34, -14), (-34, 14)]
    for (x, z), poses in labels.items():
        text = ("poses " if len(poses) > 1 else "pose ") + ", ".join(poses)
        for k, offset in enumerate(offsets):
            t = ax.annotate(text, (x, z), textcoords="offset points", xytext=offset, fontsize=7, ha="center",
                            va="center", zorder=3, bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none",
                                                            alpha=0.85))
            box = t.get_window_extent(renderer).expanded(1.05, 1.1)
            if not any(box.overlaps(other) for other in kept) or k == len(offsets) - 1:
                kept.append(box)
                break
            t.remove()


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("plan")
    ap.add_argument("png")
    ap.add_argument("--workspace")
    ap.add_argument("--frame", type=pair, required=True)
    ap.add_argument("--exit", type=pair, action="append", default=[])
    ap.add_argument("--anchor", type=pair, action="append", default=[])
    ap.add_argument("--title", default="Measurement poses")
    args = ap.parse_args()

    fig, ax = plt.subplots(figsize=(10, 5.6))
    if args.workspace:
        ws = read_csv(args.workspace)
        xs = np.array(sorted({float(r["x"]) for r in ws}))
        zs = np.array(sorted({float(r["z"]) for r in ws}))
        ix = {v: i for i, v in enumerate(xs)}
        iz = {v: i for i, v in enumerate(zs)}
        feas = np.zeros((len(zs), len(xs)))
        for r in ws:
            feas[iz[float(r["z"])], ix[float(r["x"])]] = 1.0 if r["feasible"] == "1" else np.nan
        step = xs[1] - xs[0]
        ax.imshow(feas, origin="lower", cmap="Greens", vmin=0, vmax=4, aspect="equal",
                  extent=(xs[0] - step / 2, xs[-1] + step / 2, zs[0] - step / 2, zs[-1] + step / 2))
    w, h = args.frame
    ax.plot([0, w, w, 0, 0], [0, 0, h, h, 0], color="black", lw=1.5)
    for x, z in args.exit:
        ax.plot(x, z, "rv", ms=9)
    # Information-based designs repeat poses: one label per place, listing its pose numbers.
    labels = {}
    for row in read_csv(args.plan):
        x, z, th = float(row["x"]), float(row["z"]), float(row["theta"])
        labels.setdefault((round(x, 3), round(z, 3)), []).append(row["pose"])
        c, s = math.cos(th), math.sin(th)
        anchors = [(x + c * bx - s * bz, z + s * bx + c * bz) for bx, bz in args.anchor]
        for (ax_, az_), (ex, ez) in zip(anchors, args.exit):
            ax.plot([ax_, ex], [az_, ez], color="0.6", lw=0.5, zorder=1)
        ax.plot([p[0] for p in anchors], [p[1] for p in anchors], color="tab:blue", lw=2.5, zorder=2)
    ax.set_title(args.title, fontsize=10)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_xlim(-0.2, w + 0.2)
    ax.set_ylim(-0.2, h + 0.3)
    ax.set_aspect("equal")
    # Legend entries for what the plot draws (proxies: the real artists repeat per pose).
    handles = [Patch(facecolor=plt.get_cmap("Greens")(0.25), label="feasible workspace (nominal)")] if args.workspace else []
    handles += [Line2D([], [], color="black", lw=1.5, label="frame"),
                Line2D([], [], color="red", marker="v", ls="none", ms=8, label="exit points"),
                Line2D([], [], color="tab:blue", lw=2.5, label="platform at a pose (anchors joined)"),
                Line2D([], [], color="0.6", lw=0.8, label="cables")]
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=len(handles), fontsize=8,
              frameon=False)
    fig.tight_layout()
    place_labels(fig, ax, labels)
    fig.savefig(args.png, dpi=120, format="png")
    return 0


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # Ctrl-C stops it quietly: cablecal reports it
    sys.exit(main())
