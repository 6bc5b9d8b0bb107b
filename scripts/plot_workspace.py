#!/usr/bin/python3
"""Draws a workspace CSV written by `cablecal workspace`: the feasible region, the cable
tension levels over it, the frame, the exit points and the home pose.

Called by `cablecal workspace --plot`; usable alone:
  /usr/bin/python3 scripts/plot_workspace.py ws.csv out.png --frame 5.209,2.8 \
      --exit 0,2.8 --exit 5.209,2.8 --home 2.6045,1.4
"""
import argparse
import csv
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
import numpy as np  # noqa: E402


def pair(text):
    a, b = text.split(",")
    return float(a), float(b)


def hide_overlapping(fig, texts):
    """Hides every contour label that would overlap one drawn before it (where contours crowd,
    as near the top of a suspended robot's workspace)."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    kept = []
    for text in texts:
        box = text.get_window_extent(renderer).expanded(1.15, 1.3)
        if any(box.overlaps(other) for other in kept):
            text.set_visible(False)
        else:
            kept.append(box)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("csv")
    ap.add_argument("png")
    ap.add_argument("--frame", type=pair, required=True)
    ap.add_argument("--exit", type=pair, action="append", default=[])
    ap.add_argument("--home", type=pair)
    ap.add_argument("--title", default="Feasible cable-tension workspace")
    args = ap.parse_args()

    with open(args.csv, newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    xs = np.array(sorted({float(r["x"]) for r in rows}))
    zs = np.array(sorted({float(r["z"]) for r in rows}))
    ix = {v: i for i, v in enumerate(xs)}
    iz = {v: i for i, v in enumerate(zs)}
    tension_cols = [c for c in rows[0].keys() if c.startswith("t") and c[1:].isdigit()]
    feas = np.zeros((len(zs), len(xs)), dtype=bool)
    tmax = np.full((len(zs), len(xs)), np.nan)
    t = {c: np.full((len(zs), len(xs)), np.nan) for c in tension_cols}
    for r in rows:
        i, j = iz[float(r["z"])], ix[float(r["x"])]
        feas[i, j] = r["feasible"] == "1"
        if r["feasible"] == "1":
            for c in tension_cols:
                t[c][i, j] = float(r[c])
            tmax[i, j] = max(float(r[c]) for c in tension_cols)

    fig, ax = plt.subplots(figsize=(10, 5.6))
    step = xs[1] - xs[0] if len(xs) > 1 else 0.05
    extent = (xs[0] - step / 2, xs[-1] + step / 2, zs[0] - step / 2, zs[-1] + step / 2)
    im = ax.imshow(np.where(feas, tmax, np.nan), origin="lower", extent=extent, cmap="viridis",
                   aspect="equal", interpolation="nearest")
    fig.colorbar(im, ax=ax, label="largest cable tension (N)", shrink=0.8)
    # One line style per cable, eight of them (the most cables a robot file has).
    styles = ["-", "--", ":", "-.", (0, (8, 2)), (0, (3, 1, 1, 1, 1, 1)), (0, (1, 3)), (0, (6, 2, 1, 2, 1, 2))]
    labels = []
    # Two cables: each cable's contours. More: the per-cable fields, set by a tension
    # distribution that sits on the lower bound over whole regions, give a thicket of lines;
    # the largest tension's contours say where the limit is near (per-cable tensions are in the CSV).
    if len(tension_cols) > 2 and np.isfinite(tmax).sum() > 4:
        cs = ax.contour(xs, zs, tmax, levels=8, colors="white", linewidths=0.8)
        labels += ax.clabel(cs, fontsize=7, fmt="%.0f N")
        ax.plot([], [], color="0.35", lw=1.2, label="largest-tension contours (N)")
    for k, c in enumerate(tension_cols if len(tension_cols) <= 2 else []):
        if np.isfinite(t[c]).sum() > 4:
            cs = ax.contour(xs, zs, t[c], levels=8, colors="white", linestyles=[styles[k % len(styles)]],
                            linewidths=0.8)
            labels += ax.clabel(cs, fontsize=7, fmt="%.0f N")
            # The legend's sample of this cable's contours (white would vanish on the legend).
            ax.plot([], [], color="0.35", linestyle=styles[k % len(styles)], lw=1.2, label=f"{c} contours (N)")
    w, h = args.frame
    ax.plot([0, w, w, 0, 0], [0, 0, h, h, 0], color="black", lw=1.5, label="frame")
    for k, (x, z) in enumerate(args.exit):
        ax.plot(x, z, "rv", ms=9, label="exit points" if k == 0 else None)
    if args.home:
        ax.plot(*args.home, "w*", ms=12, mec="black", label="home")
    area = feas.sum() * step * step
    # With 3 or more cables each point shows the pose at the middle of its feasible theta band
    # (the CSV's theta_min, theta_max columns).
    band = "\n(tensions at the middle of each point's feasible theta band)" if "theta_min" in rows[0] else ""
    ax.set_title(f"{args.title}: {feas.sum()} feasible grid points, area ~ {area:.2f} m$^2${band}", fontsize=10)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_xlim(-0.2, w + 0.2)
    ax.set_ylim(-0.2, h + 0.3)
    # Below the map, where it hides no exit point or contour.
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=6, fontsize=8,
              frameon=False)
    fig.tight_layout()
    hide_overlapping(fig, labels)
    fig.savefig(args.png, dpi=120, format="png")
    return 0


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # Ctrl-C stops it quietly: cablecal reports it
    sys.exit(main())
