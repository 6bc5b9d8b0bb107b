#!/usr/bin/python3
"""An independent identification of bench/spatial_experiment.h's problem with scipy, for bench/.

cogiro (robots/cogiro.yaml, taken as inextensible) with an inclinometer (sigma 1 mrad: RangedNoise{0.003, 0}, a 3-sigma range) and a
vertical laser (0.1 mm) added; the ml estimator: every reading whitened by its sensor's sigma,
unknowns the exit points and initial lengths (the coordinates cablecal's default gauge held,
given on the command line, fixed at nominal) and each pose's (x, y, z, roll, pitch, yaw).
The swivel-pulley cable model written for this bench in numpy from the README's description
(arc over the pulley plus free segment, the pulley turning about its fixed axis), R = Rz Ry Rx.

scipy.optimize.least_squares, Levenberg-Marquardt (MINPACK), dense Jacobian by 2-point
differences, x_scale='jac' (trust-region reflective with LSMR and the Jacobian's sparsity
did not converge in 2000 evaluations on 30 poses: cost stuck at 23.5); start: nominal geometry, each pose at
home's x, y and yaw with z from the laser and roll, pitch from the inclinometer.

  scipy_spatial_identify.py ROBOT.yaml READINGS.csv REPETITIONS HELD_NAME...

Prints the median wall time (s) and the estimates in time_spatial_identify's format.
"""
import sys
import time

import numpy as np
import yaml
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix


def rotation(roll, pitch, yaw):
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    R = np.empty(roll.shape + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
    R[..., 1, 0], R[..., 1, 1], R[..., 1, 2] = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
    R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = -sp, cp * sr, cp * cr
    return R


def lengths(exits, k, r, anchors_F):
    """exits (m,3), k (m,3), r (m,), anchors_F (n,m,3) -> (n,m) cable lengths over the pulleys."""
    rho = anchors_F - exits[None]
    rho_k = np.einsum("nmi,mi->nm", rho, k)
    rho_perp = rho - rho_k[..., None] * k[None]
    m_u = np.linalg.norm(rho_perp, axis=2) - r[None]
    m_k = rho_k
    m2 = m_u ** 2 + m_k ** 2
    free = np.sqrt(m2 - r[None] ** 2)
    phi = np.arctan2(m_k * r[None] + m_u * free, m_u * r[None] - m_k * free)
    return r[None] * (np.pi - phi) + free


def main():
    robot_path, readings_path, repetitions = sys.argv[1], sys.argv[2], int(sys.argv[3])
    held = sys.argv[4:]
    robot = yaml.safe_load(open(robot_path))
    cables = robot["cables"]
    m = len(cables)
    exits0 = np.array([c["exit"] for c in cables], float)
    k = np.array([c["swivel_axis"] for c in cables], float)
    k /= np.linalg.norm(k, axis=1)[:, None]
    r = np.array([c["pulley_radius"] for c in cables], float)
    anchors = np.array(robot["platform"]["anchors"], float)
    floor_z = robot["frame"]["min"][2]
    home = np.array(robot["home"] + [0.0, 0.0, 0.0])
    s_enc, s_inc, s_las = robot["sensors"]["encoder"]["sigma"], 0.001, 0.0001

    rows = [line for line in open(readings_path) if line.strip() and not line.startswith("#")]
    header = rows[0].strip().split(",")
    data = np.array([[float(v) for v in line.split(",")] for line in rows[1:]])
    dl = data[:, [header.index("dl%d" % (i + 1)) for i in range(m)]]
    incl = data[:, [header.index("roll"), header.index("pitch")]]
    laser = data[:, header.index("z")]
    n = len(data)

    def pose_lengths(exits, poses):
        R = rotation(poses[:, 3], poses[:, 4], poses[:, 5])
        anchors_F = poses[:, None, :3] + np.einsum("nij,mj->nmi", R, anchors)
        return lengths(exits, k, r, anchors_F)

    names = ["a%d%s" % (i + 1, a) for i in range(m) for a in "xyz"] + ["l%d0" % (i + 1) for i in range(m)]
    g0 = np.concatenate([exits0.ravel(), pose_lengths(exits0, home[None])[0]])
    free = [j for j, name in enumerate(names) if name not in held]
    pf = len(free)

    def unpack(x):
        g = g0.copy()
        g[free] = x[:pf]
        return g, x[pf:].reshape(n, 6)

    def residuals(x):
        g, poses = unpack(x)
        exits, l0 = g[:3 * m].reshape(m, 3), g[3 * m:]
        enc = (pose_lengths(exits, poses) - l0[None] - dl) / s_enc
        inc = (poses[:, 3:5] - incl) / s_inc
        las = (poses[:, 2] - floor_z - laser) / s_las
        return np.concatenate([enc.ravel(), inc.ravel(), las])

    sparsity = lil_matrix((11 * n, pf + 6 * n), dtype=int)
    column = {j: c for c, j in enumerate(free)}
    for j in range(n):
        for i in range(m):
            row = j * m + i
            for c in [3 * i, 3 * i + 1, 3 * i + 2, 3 * m + i]:
                if c in column:
                    sparsity[row, column[c]] = 1
            sparsity[row, pf + 6 * j: pf + 6 * j + 6] = 1
        for a in range(2):
            sparsity[m * n + 2 * j + a, pf + 6 * j + 3 + a] = 1
        sparsity[(m + 2) * n + j, pf + 6 * j + 2] = 1

    start_poses = np.tile(home, (n, 1))
    start_poses[:, 2] = laser + floor_z
    start_poses[:, 3:5] = incl
    x0 = np.concatenate([g0[free], start_poses.ravel()])
    times = []
    for _ in range(repetitions):
        t0 = time.perf_counter()
        result = least_squares(residuals, x0, method="lm", x_scale="jac", ftol=1e-10, xtol=1e-10, gtol=1e-12)
        times.append(time.perf_counter() - t0)
    g, _ = unpack(result.x)
    print("median_s %.9g" % np.median(times))
    print("status %d nfev %d cost %.6g" % (result.status, result.nfev, result.cost))
    for name, value in zip(names, g):
        print("%s %.17g" % (name, value))


if __name__ == "__main__":
    main()
