#!/usr/bin/env python3
"""What of Fennel et al. 2022 (Figure 5, section VII) a haptic 6R design can be compared with.

Evaluates one design of a haptic6r study on its human-arm scene sample by sample and prints:
  - J_x, J_v, J_a, J_f of the whole scene;
  - J_x per height of the palm above the shoulder (z_B), the paper's "close to 1 at chest height,
    lower for poses high or low relative to the chest";
  - the mean velocity and acceleration ratios eta_v, eta_a over the reached poses per band of q4,
    the paper's "J_v falls off where q4 nears 0 or 180 deg, J_a is lowest near q4 = 90 deg";
  - the gravity torque of joint 4: its largest magnitude over the reached poses and near
    q4 = 90 deg (the paper: about 21 N m for its design and actuators).

    PYTHONPATH=build/python /usr/bin/python3 scripts/compare-with-fennel.py problems/haptic6r-evaluate.json
    PYTHONPATH=build/python /usr/bin/python3 scripts/compare-with-fennel.py problems/haptic6r-ga-paper.json \\
        --design results/haptic6r-ga-paper/result.json
"""
import argparse
import json
import sys

import numpy as np

import hapsyn


def local_column(names, suffix):
    """The first local column of the coverage metric whose name ends in `suffix`."""
    for k, name in enumerate(names):
        if name.split("[")[0].endswith(suffix):
            return k
    sys.exit(f"compare-with-fennel: no local value '{suffix}' among {names}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("problem", help="a haptic6r study on the human_arm scene")
    parser.add_argument("--design", help="a result.json whose best design to evaluate (default: the study's own)")
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    with open(args.problem) as f:
        problem = json.load(f)
    if args.design:
        with open(args.design) as f:
            best = json.load(f)["best"]["design"]
        problem["design"] = {name: {"value": value} for name, value in best.items()}
    # The study's design, fixed, evaluated with one coverage objective (all four terms).
    problem["solver"] = {"plugin": "evaluate"}
    problem["objectives"] = [{"metric": "coverage"}]
    study = hapsyn.load(problem, set=[f"threads={args.threads}"])
    if study.dimension != 0:
        sys.exit(f"compare-with-fennel: the design has free variables {study.free_names}; give --design")
    design = np.zeros(0)
    e = study.evaluate(design, samples=True, quantities=["gravity"])
    status = e["sample_status"]
    names = e["local_names"]
    locals_ = e["locals"]
    q4 = np.degrees(e["quantities"]["q"][:, 3])
    g4 = e["quantities"]["gravity"][:, 3]
    reached = status == "reachable"
    scene = study.scene
    shoulder_z = study.resolved["scene"]["options"]["x_S_B"][2]
    height = scene.samples[:, 2] - shoulder_z
    eta_v = locals_[:, local_column(names, "eta_v")]
    eta_a = locals_[:, local_column(names, "eta_a")]
    eta_f = locals_[:, local_column(names, "eta_f")]
    n = len(status)
    print(f"design: {json.dumps(study.resolved['design'])}")
    print(f"poses {n}, reached {reached.sum()}: J_x {reached.mean():.3f}, J_v {eta_v[reached].mean():.3f}, "
          f"J_a {eta_a[reached].mean():.3f}, J_f {eta_f[reached].mean():.3f}")
    print("\nJ_x per height of the palm above the shoulder (z_B):")
    print("| height [m] | human poses | J_x |")
    print("|---:|---:|---:|")
    for h in np.unique(np.round(height, 3))[::-1]:
        at = np.abs(height - h) < 1e-6
        print(f"| {h:+.2f} | {at.sum()} | {reached[at].mean():.3f} |")
    print("\nMean eta_v, eta_a over the reached poses per band of q4:")
    print("| q4 [deg] | reached poses | eta_v | eta_a |")
    print("|---|---:|---:|---:|")
    for lo in range(0, 180, 20):
        band = reached & (q4 >= lo) & (q4 < lo + 20)
        if band.any():
            print(f"| {lo}-{lo + 20} | {band.sum()} | {eta_v[band].mean():.3f} | {eta_a[band].mean():.3f} |")
    print("\nGravity torque of joint 4 over the reached poses:")
    k = np.argmax(np.abs(np.where(reached, g4, 0.0)))
    near = reached & (np.abs(q4 - 90.0) < 5.0)
    print(f"  largest |tau_g4| = {abs(g4[k]):.2f} N m at q4 = {q4[k]:.1f} deg")
    if near.any():
        print(f"  largest |tau_g4| with q4 within 5 deg of 90 = {np.abs(g4[near]).max():.2f} N m ({near.sum()} poses)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
