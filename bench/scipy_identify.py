#!/usr/bin/python3
"""An independent identification of a cablecal measurement file with scipy, for bench/.

The same problem cablecal's Monte Carlo solves per trial: the maximum-likelihood
(errors-in-variables) estimator, gauge a1x (exit point 1's x held at nominal), every reading
whitened by its sensor's sigma; unknowns a1z a2x ... amz, l10 ... lm0 and each pose's
(x, z, theta). Written for this bench from the README's model ("Model and conventions"), not
from cablecal's code: cable length = pulley arc + straight segment, with the wrap angle from
the tangency construction.

As a competent scipy user would solve it: scipy.optimize.least_squares, Levenberg-Marquardt
(MINPACK), with the dense Jacobian by central differences grouped through its block
structure (each pose's rows touch only its own 3 unknowns and the geometry, so one
perturbation moves every pose's x at once: 2 x (3 + 3m - 1) residual evaluations per
Jacobian, each vectorised over the poses), starting from the nominal geometry and each
pose's x where the nominal model best explains its lengths (a 1-D Gauss-Newton per pose,
vectorised), as cablecal starts. (least_squares' own jac_sparsity path, trust-region
reflective with LSMR, took 2.1 s at n = 50: far slower, and not what a careful user keeps.)

  scipy_identify.py ROBOT.yaml PLAN.csv MEASUREMENTS.csv [REPETITIONS]

PLAN.csv (cablecal sample/design) gives the nominal initial lengths (l_i - dl_i). Prints the
median wall time of one identification (seconds) and the estimates, in time_identify's format.
"""
import sys
import time

import numpy as np
import yaml
from scipy.optimize import least_squares


def read_csv(path):
    rows = [line.strip() for line in open(path) if line.strip() and not line.startswith("#")]
    header = rows[0].split(",")
    data = np.array([[float(v) for v in r.split(",")] for r in rows[1:]])
    return header, data


def main():
    robot_path, plan_path, meas_path = sys.argv[1:4]
    repetitions = int(sys.argv[4]) if len(sys.argv) > 4 else 20
    robot = yaml.safe_load(open(robot_path))
    cables = robot["cables"]
    m = len(cables)
    anchors = np.array(robot["platform"]["anchors"], dtype=float)        # (m, 2), platform frame
    radius = np.array([c["pulley_radius"] for c in cables], dtype=float)
    side = np.array([1.0 if c["side"] == "left" else -1.0 for c in cables])
    wrap = np.array([-1.0 if c.get("wrap", "over") == "under" else 1.0 for c in cables])
    exits = np.array([c["exit"] for c in cables], dtype=float)          # (m, 2)
    s = robot["sensors"]
    sigma_enc = s["encoder"]["sigma"]
    sigma_laser = np.hypot(s["laser"]["accuracy"], s["laser"]["repeatability"]) / 3.0
    sigma_incl = np.radians(np.hypot(s["inclinometer"]["accuracy_deg"], s["inclinometer"]["repeatability_deg"])) / 3.0

    plan_header, plan = read_csv(plan_path)
    l_cols = [plan_header.index("l%d" % (i + 1)) for i in range(m)]
    dl_cols = [plan_header.index("dl%d" % (i + 1)) for i in range(m)]
    l0_nominal = plan[0, l_cols] - plan[0, dl_cols]

    header, meas = read_csv(meas_path)
    dl = meas[:, [header.index("dl%d" % (i + 1)) for i in range(m)]]   # (n, m)
    z_meas = meas[:, header.index("z")]
    theta_meas = meas[:, header.index("theta")]
    n = len(meas)

    def lengths(exit_xz, x, z, theta):
        """Cable lengths (n, m) for exit points (m, 2) and poses (n,)."""
        c, sn = np.cos(theta)[:, None], np.sin(theta)[:, None]
        bx = x[:, None] + c * anchors[:, 0] - sn * anchors[:, 1]
        bz = z[:, None] + sn * anchors[:, 0] + c * anchors[:, 1]
        mx = side * (bx - (exit_xz[:, 0] + side * radius))
        mz = wrap * (bz - exit_xz[:, 1])
        seg = np.sqrt(mx * mx + mz * mz - radius * radius)
        alpha = np.arctan2(mz * radius + mx * seg, mx * radius - mz * seg)
        return radius * (np.pi - alpha) + seg

    a1x = exits[0, 0]
    geometry_nominal = np.concatenate([exits.reshape(-1)[1:], l0_nominal])  # a1x held
    g_count = len(geometry_nominal)

    def unpack(p):
        g = np.concatenate([[a1x], p[:g_count]])
        exit_xz = g[: 2 * m].reshape(m, 2)
        l0 = g[2 * m:]
        pose = p[g_count:].reshape(n, 3)
        return exit_xz, l0, pose

    def residuals(p):
        exit_xz, l0, pose = unpack(p)
        r_len = (lengths(exit_xz, pose[:, 0], pose[:, 1], pose[:, 2]) - (dl + l0)) / sigma_enc
        r_z = (pose[:, 1] - z_meas) / sigma_laser
        r_t = (pose[:, 2] - theta_meas) / sigma_incl
        return np.concatenate([r_len, r_z[:, None], r_t[:, None]], axis=1).reshape(-1)

    def jacobian(p):
        """Dense Jacobian by grouped central differences (see the module's docstring)."""
        J = np.zeros((n * (m + 2), g_count + 3 * n))
        for k in range(g_count):
            h = 1e-7 * max(1.0, abs(p[k]))
            up, down = p.copy(), p.copy()
            up[k] += h
            down[k] -= h
            J[:, k] = (residuals(up) - residuals(down)) / (2 * h)
        for k in range(3):
            h = 1e-7
            up, down = p.copy(), p.copy()
            up[g_count + k::3] += h
            down[g_count + k::3] -= h
            column = (residuals(up) - residuals(down)) / (2 * h)
            for j in range(n):
                rows = slice(j * (m + 2), (j + 1) * (m + 2))
                J[rows, g_count + 3 * j + k] = column[rows]
        return J

    def starting_x():
        # Gauss-Newton in each pose's x alone, every pose at once (their x's are independent).
        x = np.full(n, np.mean(exits[:, 0]))
        for _ in range(20):
            r = lengths(exits, x, z_meas, theta_meas) - (dl + l0_nominal)
            h = 1e-7
            d = (lengths(exits, x + h, z_meas, theta_meas) - lengths(exits, x - h, z_meas, theta_meas)) / (2 * h)
            step = (d * r).sum(axis=1) / (d * d).sum(axis=1)
            x = x - step
            if np.max(np.abs(step)) < 1e-9:
                break
        return x

    def identify():
        x0 = starting_x()
        p0 = np.concatenate([geometry_nominal, np.stack([x0, z_meas, theta_meas], axis=1).reshape(-1)])
        return least_squares(residuals, p0, jac=jacobian, method="lm", ftol=1e-12, xtol=1e-12, gtol=1e-12)

    seconds = []
    for _ in range(repetitions):
        t0 = time.perf_counter()
        solution = identify()
        seconds.append(time.perf_counter() - t0)
    if not solution.success:
        print("scipy_identify: least_squares did not converge: " + solution.message, file=sys.stderr)
        return 3
    exit_xz, l0, _ = unpack(solution.x)
    print("median_s %.9g" % np.median(seconds))
    print("iterations %d" % solution.nfev)
    for i in range(m):
        print("a%dx %.17g" % (i + 1, exit_xz[i, 0]))
        print("a%dz %.17g" % (i + 1, exit_xz[i, 1]))
    for i in range(m):
        print("l%d0 %.17g" % (i + 1, l0[i]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
