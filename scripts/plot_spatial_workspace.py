#!/usr/bin/python3
"""Draws a spatial workspace CSV written by `cablecal workspace` for a spatial robot: four
horizontal slices of the constant-orientation workspace, seen from above, each with the frame
box's outline, the exit points (drawn down-pointing above the slice, up-pointing below it) and
home; feasible cells coloured by their smallest cable tension (by the largest where the smallest
is the same everywhere, as on a fully constrained robot), the others by why they are not.

Called by `cablecal workspace --plot` for a `kind: spatial` robot; usable alone:
  /usr/bin/python3 scripts/plot_spatial_workspace.py ws.csv out.png --frame-min=-2,-1.5,0 \
      --frame-max=2,1.5,2.2 --exit=-2,-1.5,2 --exit=2,-1.5,2 --home=0,0,1
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
from matplotlib.colors import ListedColormap  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402


def triple(text):
    a, b, c = text.split(",")
    return float(a), float(b), float(c)


# Light, distinct greys and tints for the reasons a cell is not feasible (the feasible ones
# carry the tension colour map); a reason not listed gets the last.
REASON_COLOURS = {
    "tension_low": "#f4c7c3",
    "tension_high": "#f9e0b0",
    "no_equilibrium": "#d9d9d9",
    "unstable": "#e6d0f0",
    "outside_frame": "#ffffff",
    "tilt_limit": "#cfe3f3",
    "cable_geometry": "#b0b0b0",
    "swivel_axis": "#9a9a9a",
    "inside_pulley": "#9a9a9a",
    "wrap": "#c8c8a0",
}


def slice_heights(zs, feasible_by_z, count=4):
    """Up to `count` heights spread over the levels that hold feasible cells (over every level
    when none does), lowest first."""
    levels = [z for z in zs if feasible_by_z.get(z, 0) > 0] or list(zs)
    if len(levels) <= count:
        return levels
    # Inside the band rather than on its edges, where the feasible region thins to a few cells,
    # when the band has room for that many distinct levels.
    inner = [levels[int(round(k))] for k in np.linspace(0, len(levels) - 1, count + 2)[1:-1]]
    if len(set(inner)) == count:
        return inner
    return [levels[int(round(k))] for k in np.linspace(0, len(levels) - 1, count)]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("csv")
    ap.add_argument("png")
    ap.add_argument("--frame-min", type=triple, required=True)
    ap.add_argument("--frame-max", type=triple, required=True)
    ap.add_argument("--exit", type=triple, action="append", default=[])
    ap.add_argument("--home", type=triple)
    ap.add_argument("--title", default="Constant-orientation workspace")
    args = ap.parse_args()

    with open(args.csv, newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    xs = np.array(sorted({float(r["x"]) for r in rows}))
    ys = np.array(sorted({float(r["y"]) for r in rows}))
    zs = np.array(sorted({float(r["z"]) for r in rows}))
    ix = {v: i for i, v in enumerate(xs)}
    iy = {v: i for i, v in enumerate(ys)}
    tension_cols = [c for c in rows[0].keys() if c.startswith("t") and c[1:].isdigit()]
    reasons = sorted({r["reason"] for r in rows if r["feasible"] != "1"}, key=lambda s: list(REASON_COLOURS).index(s)
                     if s in REASON_COLOURS else len(REASON_COLOURS))
    reason_index = {s: k for k, s in enumerate(reasons)}
    by_z = {}
    for r in rows:
        by_z.setdefault(float(r["z"]), []).append(r)
    feasible_by_z = {z: sum(r["feasible"] == "1" for r in rs) for z, rs in by_z.items()}
    heights = slice_heights(zs, feasible_by_z)

    # The smallest tension says how far a suspended robot is from a slack cable; a fully
    # constrained robot's tension distribution keeps it on tension.min everywhere, and then the
    # largest tension (how far from the upper limit) is what varies and is drawn instead.
    def smallest(r):
        return min(float(r[c]) for c in tension_cols)

    def largest(r):
        return max(float(r[c]) for c in tension_cols)

    shown = [r for z in heights for r in by_z[z] if r["feasible"] == "1"]
    measure, measure_label = smallest, "smallest cable tension (N), feasible points"
    if shown:
        lo, hi = min(map(smallest, shown)), max(map(smallest, shown))
        if hi - lo <= 1e-6 * max(abs(hi), 1.0):
            measure, measure_label = largest, (f"largest cable tension (N), feasible points\n"
                                               f"(the smallest is {lo:.4g} N at every one)")
    # One colour scale over the slices drawn, so that equal colours are equal tensions.
    values = [measure(r) for r in shown]
    vmin, vmax = (min(values), max(values)) if values else (0.0, 1.0)
    if vmax <= vmin:
        vmax = vmin + 1.0
    reason_cmap = ListedColormap([REASON_COLOURS.get(s, "#c0c0c0") for s in reasons] or ["#ffffff"])

    (x0, y0, _), (x1, y1, _) = args.frame_min, args.frame_max
    n = len(heights)
    cols = 2 if n > 1 else 1
    rows_n = (n + 1) // 2
    span_x, span_y = x1 - x0, y1 - y0
    panel_w = 4.6
    panel_h = panel_w * span_y / span_x
    top_in, bottom_in, gap_in = 1.0, 1.3, 0.75  # suptitle; x label and legend; a panel's title and labels
    fig_w = cols * panel_w + (cols - 1) * 0.9 + 2.2
    fig_h = rows_n * panel_h + (rows_n - 1) * gap_in + top_in + bottom_in
    fig, axes = plt.subplots(rows_n, cols, figsize=(fig_w, fig_h), squeeze=False)
    fig.subplots_adjust(left=0.9 / fig_w, right=1 - 1.3 / fig_w, top=1 - top_in / fig_h, bottom=bottom_in / fig_h,
                        hspace=gap_in / panel_h, wspace=0.9 / panel_w)
    step = xs[1] - xs[0] if len(xs) > 1 else 0.1
    extent = (xs[0] - step / 2, xs[-1] + step / 2, ys[0] - step / 2, ys[-1] + step / 2)
    image = None
    any_below = False
    for k, z in enumerate(heights):
        ax = axes[k // cols][k % cols]
        tmin = np.full((len(ys), len(xs)), np.nan)
        why = np.full((len(ys), len(xs)), np.nan)
        for r in by_z[z]:
            i, j = iy[float(r["y"])], ix[float(r["x"])]
            if r["feasible"] == "1":
                tmin[i, j] = measure(r)
            else:
                why[i, j] = reason_index[r["reason"]]
        if reasons:
            ax.imshow(why, origin="lower", extent=extent, cmap=reason_cmap, vmin=-0.5, vmax=len(reasons) - 0.5,
                      interpolation="nearest", aspect="equal")
        image = ax.imshow(tmin, origin="lower", extent=extent, cmap="viridis", vmin=vmin, vmax=vmax,
                          interpolation="nearest", aspect="equal")
        ax.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], color="black", lw=1.5)
        for e in args.exit:
            above = e[2] >= z
            any_below |= not above
            ax.plot(e[0], e[1], "v" if above else "^", color="red" if above else "tab:blue", ms=8, mec="black",
                    mew=0.6, clip_on=False)
        if args.home:
            ax.plot(args.home[0], args.home[1], "*", color="white", ms=13, mec="black", clip_on=False)
        ax.set_title(f"z = {z:.3g} m: {feasible_by_z.get(z, 0)} of {len(by_z[z])} points feasible", fontsize=10)
        if k // cols == rows_n - 1 or k + cols >= n:
            ax.set_xlabel("x (m)")
        if k % cols == 0:
            ax.set_ylabel("y (m)")
        pad = 0.04 * max(span_x, span_y)
        ax.set_xlim(x0 - pad, x1 + pad)
        ax.set_ylim(y0 - pad, y1 + pad)
    for k in range(n, rows_n * cols):
        axes[k // cols][k % cols].axis("off")

    feasible = sum(feasible_by_z.values())
    step_z = zs[1] - zs[0] if len(zs) > 1 else step
    volume = feasible * step * step * step_z
    fig.suptitle(f"{args.title}\n{feasible} of {len(rows)} grid points feasible, volume ~ {volume:.3g} m$^3$; "
                 f"horizontal slices at {n} heights, seen from above", fontsize=10)
    handles = [plt.Line2D([], [], marker="v", ls="", color="red", mec="black", ms=8, label="exit above the slice")]
    if any_below:
        handles.append(plt.Line2D([], [], marker="^", ls="", color="tab:blue", mec="black", ms=8, label="exit below it"))
    handles += [plt.Line2D([], [], marker="*", ls="", color="white", mec="black", ms=12, label="home (x, y)"),
                plt.Line2D([], [], color="black", lw=1.5, label="frame box")]
    handles += [Patch(facecolor=REASON_COLOURS.get(s, "#c0c0c0"), edgecolor="0.5", label="infeasible: " + s.replace("_", " "))
                for s in reasons]
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 4), fontsize=8, frameon=False,
               bbox_to_anchor=(0.5, 0.0))
    cax = fig.add_axes((1 - 1.0 / fig_w, bottom_in / fig_h + 0.1, 0.18 / fig_w, 1 - (top_in + bottom_in) / fig_h - 0.2))
    fig.colorbar(image, cax=cax, label=measure_label)
    fig.savefig(args.png, dpi=110, format="png")
    return 0


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # Ctrl-C stops it quietly: cablecal reports it
    sys.exit(main())
