#!/usr/bin/env python3
"""Coverage maps of a haptic 6R design (Fennel 2022, Figure 5) from a study's samples.csv.

Reads the per-pose columns the coverage metric writes (coverage.reach_m, coverage.eta_v,
coverage.eta_a, coverage.eta_f) and aggregates them per lattice position (x, y, z of the pose
in the manipulator base B): J_x = reachable orientations / orientations, J_v, J_a, J_f = mean
eta over the reachable ones. Writes DIR/coverage_map.csv (one row per position) and prints the
terms by height z (the base is 0.61 m above the shoulder: z = -0.61 m is shoulder height).

usage: scripts/coverage-map.py results/haptic6r-ga-paper/samples.csv [OUT_DIR]
"""
import csv
import os
import sys
from collections import defaultdict


def main():
    path = sys.argv[1]
    out_dir = sys.argv[2] if len(sys.argv) > 2 else os.path.dirname(path) or "."
    with open(path) as f:
        reader = csv.reader(f)
        header = next(reader)
        col = {}
        for i, name in enumerate(header):
            col.setdefault(name, i)  # first occurrence (one per objective otherwise)
        eta = {k: col.get("coverage." + k) for k in ("eta_v", "eta_a", "eta_f")}
        reach = col["coverage.reach_m"]
        positions = defaultdict(lambda: [0, 0, 0.0, 0.0, 0.0])  # poses, reachable, sums of eta
        for row in reader:
            key = (round(float(row[col["x"]]), 6), round(float(row[col["y"]]), 6), round(float(row[col["z"]]), 6))
            p = positions[key]
            p[0] += 1
            if row[reach] and float(row[reach]) > 0.5:
                p[1] += 1
                for j, k in enumerate(("eta_v", "eta_a", "eta_f")):
                    if eta[k] is not None and row[eta[k]]:
                        p[2 + j] += float(row[eta[k]])
    os.makedirs(out_dir, exist_ok=True)
    out = os.path.join(out_dir, "coverage_map.csv")
    by_height = defaultdict(lambda: [0, 0, 0.0, 0.0, 0.0])
    with open(out, "w") as f:
        f.write("x,y,z,poses,J_x,J_v,J_a,J_f\n")
        for (x, y, z), p in sorted(positions.items()):
            r = max(p[1], 1)
            f.write(f"{x},{y},{z},{p[0]},{p[1] / p[0]:.4f},{p[2] / r:.4f},{p[3] / r:.4f},{p[4] / r:.4f}\n")
            h = by_height[z]
            for j in range(5):
                h[j] += p[j]
    print(f"{out}: {len(positions)} positions")
    print("height z [m]  poses   J_x    J_v    J_a    J_f")
    for z, h in sorted(by_height.items(), reverse=True):
        r = max(h[1], 1)
        print(f"{z:11.2f}  {h[0]:6d}  {h[1] / h[0]:.3f}  {h[2] / r:.3f}  {h[3] / r:.3f}  {h[4] / r:.3f}")


if __name__ == "__main__":
    main()
