#!/usr/bin/python3
"""Calibrating in rounds: two rounds of 8 poses (the second designed with --prior from the
first's identification) against one round of 16, on the same true robots.

For each seed: draw a true robot (simulate --geometry-sigma 0.01 --truth-out), then
  one round:  design 16 -> simulate -> identify
  two rounds: design 8 -> simulate -> identify (-> calibrated robot, result.yaml)
              design 8 --prior result.yaml on the calibrated robot -> simulate on the same
              true robot -> identify all 16 readings together
and record each parameter's predicted sigma and actual error (identified - true).

Usage: bench/rounds.py [--cablecal build/cablecal] [--robot FILE] [--seeds 10]
"""
import argparse
import csv
import math
import os
import subprocess
import sys
import tempfile

import yaml

PARAMS = ["a1z", "a2x", "a2z", "l10", "l20"]


class Unholdable(Exception):
    """simulate exit 3: the true robot cannot hold a pose of the plan within its limits."""


def run(args):
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode == 3 and args[1] == "simulate":
        raise Unholdable(r.stderr.strip())
    if r.returncode != 0:
        sys.exit("failed: " + " ".join(args) + "\n" + r.stderr)


def read_rows(path):
    with open(path) as f:
        return [row for row in csv.reader(line for line in f if not line.startswith("#"))]


def concat_measurements(first, second, out):
    a, b = read_rows(first), read_rows(second)
    header, rows = a[0], a[1:]
    offset = len(rows)
    for row in b[1:]:
        rows.append([str(int(row[0]) + offset)] + row[1:])
    with open(out, "w") as f:
        f.write(",".join(header) + "\n")
        for row in rows:
            f.write(",".join(row) + "\n")


def result(path, truth):
    with open(path) as f:
        r = yaml.safe_load(f)
    with open(truth) as f:
        t = yaml.safe_load(f)
    true = {"a1z": t["cables"][0]["exit"][1], "a2x": t["cables"][1]["exit"][0], "a2z": t["cables"][1]["exit"][1],
            "l10": t["cables"][0]["initial_length"], "l20": t["cables"][1]["initial_length"]}
    return {p: (r["parameters"][p]["std"], r["parameters"][p]["value"] - true[p]) for p in PARAMS}


def one_seed(cc, robot, seed, j, out):
    s = str(seed)
    # One round of 16; its simulation also draws the true robot both arms use.
    run(cc + ["design"] + robot + ["--poses", "16", "--starts", "4", "--seed", s, "--random-sets", "0",
                                   "--out", j("p16.csv")])
    run(cc + ["simulate"] + robot + ["--plan", j("p16.csv"), "--geometry-sigma", "0.01", "--seed", s,
                                     "--out", j("m16.csv"), "--truth-out", j("truth.yaml")])
    run(cc + ["identify"] + robot + ["--measurements", j("m16.csv"), "--out", j("r16.yaml")])
    # Two rounds of 8 on the same true robot.
    run(cc + ["design"] + robot + ["--poses", "8", "--starts", "4", "--seed", s, "--random-sets", "0",
                                   "--out", j("p8a.csv")])
    run(cc + ["simulate"] + robot + ["--plan", j("p8a.csv"), "--truth", j("truth.yaml"), "--seed", s,
                                     "--out", j("m8a.csv")])
    run(cc + ["identify"] + robot + ["--measurements", j("m8a.csv"), "--out", j("r8a.yaml"),
                                     "--calibrated-robot", j("cal.yaml")])
    run(cc + ["design", "--robot", j("cal.yaml"), "--prior", j("r8a.yaml"), "--poses", "8", "--starts", "4",
              "--seed", s, "--random-sets", "0", "--out", j("p8b.csv")])
    # The second plan's encoder commands come from the calibrated robot; the encoders
    # count from the same physical home, so both rounds' readings identify together.
    run(cc + ["simulate", "--robot", j("cal.yaml"), "--plan", j("p8b.csv"), "--truth", j("truth.yaml"),
              "--seed", str(1000 + seed), "--out", j("m8b.csv")])
    concat_measurements(j("m8a.csv"), j("m8b.csv"), j("m8ab.csv"))
    run(cc + ["identify"] + robot + ["--measurements", j("m8ab.csv"), "--out", j("r8ab.yaml")])
    for arm, path in (("one round of 16", j("r16.yaml")), ("two rounds of 8", j("r8ab.yaml"))):
        for p, (sd, err) in result(path, j("truth.yaml")).items():
            out[arm][p].append((sd, err))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cablecal", default=os.path.join(os.path.dirname(__file__), "..", "build", "cablecal"))
    ap.add_argument("--robot", default=None)
    ap.add_argument("--seeds", type=int, default=10)
    a = ap.parse_args()
    cc = [a.cablecal]
    robot = ["--robot", a.robot] if a.robot else []
    out = {"one round of 16": {p: [] for p in PARAMS}, "two rounds of 8": {p: [] for p in PARAMS}}
    skipped = []
    with tempfile.TemporaryDirectory() as d:
        j = lambda name: os.path.join(d, name)
        for seed in range(1, a.seeds + 1):
            try:
                one_seed(cc, robot, seed, j, out)
            except Unholdable as e:
                skipped.append(f"seed {seed}: {e}")
    print(f"{a.seeds} true robots (geometry sigma 0.01 m), default criterion; mm")
    print("| arm | " + " | ".join(f"{p} pred. sigma / RMS error" for p in PARAMS) + " |")
    print("|---|" + "---|" * len(PARAMS))
    for arm, per in out.items():
        cells = []
        for p in PARAMS:
            sd = 1e3 * math.sqrt(sum(v[0] ** 2 for v in per[p]) / len(per[p]))
            rms = 1e3 * math.sqrt(sum(v[1] ** 2 for v in per[p]) / len(per[p]))
            cells.append(f"{sd:.2f} / {rms:.2f}")
        print(f"| {arm} | " + " | ".join(cells) + " |")
    for line in skipped:
        print("skipped (a plan the true robot could not hold):", line)


if __name__ == "__main__":
    main()
