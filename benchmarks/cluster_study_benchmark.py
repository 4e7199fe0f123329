#!/usr/bin/env python3
"""The communication overhead of MPI ranks on whole studies, measured in one run (README: "Clusters").

    python3 benchmarks/cluster_study_benchmark.py --build build [--json out.json]

For each study it runs one process x 2 threads (the baseline) and `mpirun -n 2` x 1 thread on the
same machine, one after the other, and prints the solve time, designs, time per design and the
ratio against the baseline; then cluster_benchmark's round trip of one task request (the
per-message cost). Studies: the paper-resolution culling of the five-bar (GII and GDI), and one
GA run of the paper's haptic 6R setup. Records the hapsyn version, seeds, resolved problems (in
the JSON) and the machine. 2 ranks x 1 thread on 2 cores against 1 x 2 isolates what MPI costs:
the same cores do the same work, only the messages differ.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STUDIES = [
    ("culling GII, paper resolution", "problems/fivebar-gii-culling-paper.json", []),
    ("culling GDI, paper resolution", "problems/fivebar-gdi-culling-paper.json", []),
    ("GA, paper setup, one run", "problems/haptic6r-ga-paper.json", ["solver.options.runs=1"]),
]


def run(argv, env):
    t0 = time.time()
    p = subprocess.run(argv, env=env, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"failed: {' '.join(argv)}\n{p.stderr[-3000:]}")
    return time.time() - t0, p.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--mpiexec", default="mpirun")
    ap.add_argument("--json", help="write the figures here")
    ap.add_argument("--only", help="run only studies whose name contains this")
    args = ap.parse_args()
    hapsyn = os.path.join(args.build, "bin", "hapsyn")
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    work = tempfile.mkdtemp(prefix="hapsyn-cluster-bench-")
    rows, report = [], {"studies": []}
    for name, problem, sets in STUDIES:
        if args.only and args.only not in name:
            continue
        overrides = [x for s in sets for x in ("--set", s)]
        # The scene (the human-arm cache) is built once before timing, by a validate.
        run([hapsyn, "validate", os.path.join(ROOT, problem)] + overrides, env)
        entry = {"study": name, "problem": problem, "overrides": sets, "configs": []}
        for label, prefix, threads in (("1 rank x 2 threads", [], 2),
                                       ("2 ranks x 1 thread", [args.mpiexec, "--bind-to", "none", "-n", "2"], 1)):
            out = os.path.join(work, re.sub(r"\W+", "-", name + label))
            wall, _ = run(prefix + [hapsyn, "run", os.path.join(ROOT, problem), "--threads", str(threads), "--out", out,
                                    "--quiet"] + overrides, env)
            with open(os.path.join(out, "result.json")) as f:
                result = json.load(f)
            solve = result["phases"]["solve_s"]
            designs = result["evaluations"]["designs"]
            best = result.get("best", {}).get("score")
            entry["configs"].append({"config": label, "wall_s": wall, "solve_s": solve, "designs": designs,
                                     "score": best, "seed": result["seed"], "machine": result["machine"],
                                     "version": result["hapsyn"]["version"]})
            entry["resolved_problem"] = result["problem"]
            rows.append((name, label, solve, designs, 1e6 * solve / max(designs, 1), best))
        report["studies"].append(entry)
    _, bench = run([args.mpiexec, "--bind-to", "none", "-n", "2", os.path.join(args.build, "bin", "cluster_benchmark"),
                    "--tasks", "5000"], env)
    report["cluster_benchmark"] = bench
    shutil.rmtree(work, ignore_errors=True)

    if report["studies"]:
        c = report["studies"][0]["configs"][0]
        print(f"hapsyn {c['version']} on {c['machine']}")
    print(f"{'study':34} {'config':20} {'solve s':>9} {'designs':>10} {'us/design':>10} {'vs 1x2':>7}  best score")
    base = {}
    for name, label, solve, designs, per, best in rows:
        base.setdefault(name, solve)
        print(f"{name:34} {label:20} {solve:9.2f} {designs:10d} {per:10.1f} {base[name] / solve:7.2f}  {best}")
    print(bench)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(report, f, indent=1)


if __name__ == "__main__":
    main()
