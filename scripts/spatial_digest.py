#!/usr/bin/env python3
"""The digest tables of results/spatial/README.md, from a spatial study's folder.

Usage: scripts/spatial_digest.py results/spatial/cogiro_inclinometer_laser [...]

For each configuration folder (summary.csv, errors.csv, run.yaml, as `cablecal reproduce
--study spatial` writes them) prints two Markdown tables over the geometric parameters the
gauge leaves free (run.yaml's gauge_held are left out):
  1. per n and design, from summary.csv (values in m, printed in mm): the median and largest
     standard deviation over the exit coordinates, the median over the initial lengths, the
     median |mean| (bias) over every free geometric parameter, x_all's standard deviation, and
     the failed trials;
  2. per n and design, from errors.csv: the successful trials, the median |error| over every
     (trial, free geometric parameter), and the trials whose every free geometric error is
     below 1 mm and below 5 mm.
"""
import csv
import os
import re
import statistics
import sys


def held_parameters(folder):
    with open(os.path.join(folder, "run.yaml")) as f:
        for line in f:
            if line.startswith("gauge_held:"):
                return set(re.findall(r'"([a-z0-9]+)"', line.split("#")[0]))
    raise SystemExit(f"{folder}/run.yaml: no gauge_held line")


def is_geometry(name):
    return re.fullmatch(r"a\d+[xyz]|l\d+0", name) is not None


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def cell_order(cells):
    # random and the criteria first at each n, the grids after, as summary.md lists them
    return sorted(cells, key=lambda c: (c[1].startswith("grid"), int(c[0]), c[1]))


def digest(folder):
    held = held_parameters(folder)
    free = lambda p: is_geometry(p) and p not in held
    summary = {}
    for r in rows(os.path.join(folder, "summary.csv")):
        summary.setdefault((r["n"], r["design"]), []).append(r)
    print(f"### {os.path.basename(os.path.normpath(folder))}\n")
    print("| n | design | median σ, exits (mm) | largest σ, exits (mm) | median σ, l_i0 (mm) "
          "| median \\|mean\\|, geometry (mm) | x_all σ (mm) | failed |")
    print("|---|---|---|---|---|---|---|---|")
    for cell in cell_order(summary):
        cells = summary[cell]
        failed = int(cells[0]["failures"])
        stats = {r["parameter"]: r for r in cells}
        if any(r["std"] in ("", "nan") for r in cells if free(r["parameter"])):
            print(f"| {cell[0]} | {cell[1]} | n/a | n/a | n/a | n/a | n/a | {failed} |")
            continue
        exits = [(1e3 * float(r["std"]), p) for p, r in stats.items() if free(p) and p.startswith("a")]
        lengths = [1e3 * float(r["std"]) for p, r in stats.items() if free(p) and p.startswith("l")]
        bias = [1e3 * abs(float(r["mean"])) for p, r in stats.items() if free(p)]
        largest = max(exits)
        print(f"| {cell[0]} | {cell[1]} | {statistics.median(s for s, _ in exits):.3f} | "
              f"{largest[0]:.3f} ({largest[1]}) | {statistics.median(lengths):.3f} | "
              f"{statistics.median(bias):.3f} | {1e3 * float(stats['x_all']['std']):.3f} | {failed} |")
    trials = {}
    for r in rows(os.path.join(folder, "errors.csv")):
        if free(r["parameter"]):
            trials.setdefault((r["n"], r["design"]), {}).setdefault(r["trial"], []).append(
                1e3 * abs(float(r["error"])))
    print("\n| n | design | successful trials | median \\|error\\|, geometry (mm) "
          "| trials with every geometric error below 1 mm | below 5 mm |")
    print("|---|---|---|---|---|---|")
    for cell in cell_order(trials):
        errors = trials[cell]
        pooled = [e for t in errors.values() for e in t]
        below = lambda mm: sum(1 for t in errors.values() if max(t) < mm)
        print(f"| {cell[0]} | {cell[1]} | {len(errors)} | {statistics.median(pooled):.3f} | {below(1.0)} | "
              f"{below(5.0)} |")
    print()


if __name__ == "__main__":
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    for folder in sys.argv[1:]:
        digest(folder)
