#!/usr/bin/env python3
"""Plan 12 measurement poses, simulate the experiment on a robot whose true geometry is off by
about 1 cm, identify it, and compare the estimate with the truth, with a figure.

    PYTHONPATH=build/python /usr/bin/python3 examples/plan_and_calibrate.py --out /tmp/example
    (add --robot robots/planar3_suspended.yaml for another robot)

Prints one line per geometric parameter (nominal, true, identified +- sigma, error in sigmas)
and writes calibration.png into --out. The tests run it (tests/CMakeLists.txt).
"""
import argparse
import os
import sys

import cablecal  # before numpy and matplotlib: see README, "Python"
import numpy as np


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", help="robot YAML file (default: the built-in wang2022 robot)")
    parser.add_argument("--out", required=True, help="folder for calibration.png")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()

    robot = cablecal.Robot.load(args.robot) if args.robot else cablecal.Robot.builtin()
    design = cablecal.design(robot, 12, seed=args.seed)
    print(f"planned 12 poses of {robot.name}: trace of the covariance "
          f"{design.criteria['a_trace_covariance_m2']:.3g} m^2 "
          f"(median of random sets {design.random_median['a_trace_covariance_m2']:.3g} m^2)")

    experiment = cablecal.simulate(robot, design.plan, geometry_sigma=0.01, seed=args.seed)
    result = cablecal.identify(robot, experiment.measurements)

    names = result.geometry_names
    nominal, truth = robot.geometry, experiment.truth.geometry
    estimate, sigma = result.geometry, result.std
    print(f"{'':5}{'nominal m':>12}{'true m':>12}{'identified m':>14}{'sigma mm':>10}{'error/sigma':>13}")
    for k, name in enumerate(names):
        ratio = f"{(estimate[k] - truth[k]) / sigma[k]:13.2f}" if sigma[k] > 0 else f"{'held (gauge)':>13}"
        print(f"{name:5}{nominal[k]:12.5f}{truth[k]:12.5f}{estimate[k]:14.5f}{1e3 * sigma[k]:10.3f}{ratio}")
    estimated = sigma > 0
    before = np.abs(nominal - truth)[estimated]
    after = np.abs(estimate - truth)[estimated]
    print(f"largest error: nominal {1e3 * before.max():.2f} mm, calibrated {1e3 * after.max():.3f} mm")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(args.out, exist_ok=True)
    fig, (ax_plan, ax_err) = plt.subplots(1, 2, figsize=(11, 4.5))
    q = design.plan.poses
    ax_plan.plot(q[:, 0], q[:, 1], "o", color="tab:blue", label="designed poses (numbers: pose ids)")
    # Optimal designs repeat poses: one label per place, listing every pose measured there.
    places = {}
    for j, (x, z) in enumerate(q[:, :2], start=1):
        places.setdefault((round(x, 3), round(z, 3)), []).append(str(j))
    # Each label at the first of a few offsets where it overlaps no label placed before it.
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    kept = []
    for (x, z), ids in places.items():
        for k, offset in enumerate([(6, 6), (6, -10), (-14, 6), (-14, -10), (6, 16), (6, -20)]):
            label = ax_plan.annotate(", ".join(ids), (x, z), textcoords="offset points", xytext=offset, fontsize=8)
            box = label.get_window_extent(renderer)
            if not any(box.overlaps(other) for other in kept) or k == 5:
                kept.append(box)
                break
            label.remove()
    ax_plan.set_xlabel("x (m)")
    ax_plan.set_ylabel("z (m)")
    ax_plan.set_title(f"{robot.name}: 12 designed poses")
    ax_plan.set_aspect("equal", adjustable="datalim")
    ax_plan.legend(loc="best")

    positions = np.arange(estimated.sum())
    labels = [n for n, e in zip(names, estimated) if e]
    ax_err.bar(positions - 0.2, 1e3 * before, width=0.4, color="tab:gray", label="nominal robot (uncalibrated)")
    ax_err.bar(positions + 0.2, 1e3 * after, width=0.4, color="tab:green", label="identified")
    ax_err.plot(positions + 0.2, 1e3 * sigma[estimated], "_", color="black", markersize=18, markeredgewidth=2,
                label="identified: predicted 1 sigma")
    ax_err.set_xticks(positions, labels)
    ax_err.set_ylabel("|error| against the true robot (mm)")
    ax_err.set_title("geometry error (a1x is held: it fixes the frame)")
    ax_err.legend(loc="upper left", fontsize=8)
    ax_err.set_ylim(0, 1.35 * 1e3 * max(before.max(), after.max(), sigma.max()))
    fig.tight_layout()
    path = os.path.join(args.out, "calibration.png")
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except (cablecal.InputError, cablecal.SolverError) as e:
        print(f"plan_and_calibrate: {e}", file=sys.stderr)
        sys.exit(2 if isinstance(e, cablecal.InputError) else 3)
