#!/usr/bin/env python3
"""hapsyn against its Python peers on the five-bar studies, in one run on one machine (issue 16).

    HAPSYN_EXTRA_PACKAGES="python3-numba python3-deap" bash scripts/setup.sh && \\
        /usr/bin/python3 benchmarks/fivebar_speed.py --out build/fivebar_speed.json

Rows (the peers are benchmarks/fivebar_peers.py; ratio = hapsyn seconds / peer seconds, below 1
means hapsyn is faster):

- grid: the exhaustive 10 mm GII search of problems/fivebar-gii-coarse.json (1,701,900 designs,
  441 samples), unpruned and pruned, 1 and 2 threads: `hapsyn run` of a copy of the file with
  "prune": false / true and --threads N (its solve time, result.json phases.solve_s; the best of
  --repeats runs, as the peer) against numba-grid with the same threads and pruning (best of
  --repeats timed runs, JIT excluded). Each numba run checks hapsyn's optimum (value to 1e-9
  relative, same design) and, unpruned, its feasible / reach-violated / sample-failed counts.
- nsga2: problems/fivebar-pareto-nsga2.json (population 200, 3000 generations, its seed) with
  --threads 2 and 1 against DEAP's NSGA-II (deap-nsga2, same population, generations and seed,
  its numba batch evaluation on 2 threads); both hypervolumes, reference point (0, 0) in
  natural units (hapsyn's: result.json indicators.hypervolume with
  indicators.reference_point = [0, 0] set on the command line, since the file sets none).
- numpy: the plain NumPy exhaustive 10 mm GII search on one core (numpy-grid), with the
  optimum check; the reference of the culling target. The best of --paper-repeats runs (3).
- paper: the paper-resolution culling studies problems/fivebar-gii-culling-paper.json and
  fivebar-gdi-culling-paper.json (--threads 2), as a ratio against the NumPy search, each also
  with solver.options.block_bounds=false (the sweep without block bounds, docs/design.md
  section 13.5) as the same run's baseline; the best of --paper-repeats runs each (3), as the
  NumPy search. Up to a minute each; --skip-paper leaves them out.

Options: --hapsyn PATH (default $HAPSYN, else build/bin/hapsyn under the repository root),
--only grid,nsga2,numpy,paper, --repeats N (3), --paper-repeats N (3), --out FILE (JSON: every figure, the hapsyn
version (git describe, hapsyn --version), seeds, the resolved problem files, the machine (lscpu
model name, avx512f/avx2 flags, cores), the date and the load average around each row).
The machine may be shared: the load average before and after each row is recorded, and
--wait-load LOAD (e.g. 0.7) makes each row wait until the 1-minute load average is below LOAD
(at most --wait-max seconds, 900) so that no row starts while another job is busy; compare
ratios, not bare seconds. The one-thread rows (hapsyn, numba, numpy) run on one CPU, both sides
alike (`taskset -c`, --pin CPU, default the highest-numbered one; --no-pin lets the OS place
them): on a 2-core VM seen here, hapsyn's pruned grid took 24 to 25 ms on CPU 1 and 31 to 37 ms
on CPU 0 in alternated runs, and a fresh process lands on either.
"""
import argparse
import copy
import datetime
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PEERS = os.path.join(ROOT, "benchmarks", "fivebar_peers.py")
GRID = "problems/fivebar-gii-coarse.json"
NSGA2 = "problems/fivebar-pareto-nsga2.json"
PAPER = [("culling GII, paper resolution", "problems/fivebar-gii-culling-paper.json"),
         ("culling GDI, paper resolution", "problems/fivebar-gdi-culling-paper.json")]
ROWS = ("grid", "nsga2", "numpy", "paper")


def load():
    return [round(x, 2) for x in os.getloadavg()]


def wait_quiet(args, what):
    """With --wait-load: wait (at most --wait-max seconds) until the 1-minute load average is below
    the threshold, so that a row does not start while the machine is busy with other work."""
    if not args.wait_load:
        return 0.0
    t0 = time.time()
    while os.getloadavg()[0] >= args.wait_load and time.time() - t0 < args.wait_max:
        time.sleep(10)
    waited = time.time() - t0
    if waited > 1:
        print(f"  waited {waited:.0f} s for load < {args.wait_load} before {what} (now {load()})", file=sys.stderr,
              flush=True)
    return waited


def machine():
    info = {"python": platform.python_version(), "cores": os.cpu_count()}
    try:
        text = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    except OSError:
        text = ""
    fields = dict(re.findall(r"^([^:\n]+):\s*(.*)$", text, re.M))
    info["model_name"] = fields.get("Model name", platform.processor())
    flags = fields.get("Flags", "").split()
    info["avx512f"] = "avx512f" in flags
    info["avx2"] = "avx2" in flags
    info["fma"] = "fma" in flags
    info["cpus"] = int(fields.get("CPU(s)", os.cpu_count() or 0))
    info["threads_per_core"] = fields.get("Thread(s) per core")
    return info


def git_describe(path):
    p = subprocess.run(["git", "-C", path, "describe", "--always", "--dirty", "--tags"], capture_output=True,
                       text=True)
    return p.stdout.strip() if p.returncode == 0 else None


class Runner:
    def __init__(self, args):
        self.args = args
        self.hapsyn = args.hapsyn
        self.work = tempfile.mkdtemp(prefix="fivebar-speed-")
        self.python = sys.executable
        self.headers = {}  # result.json's "hapsyn" and "machine" of the first run

    def pinned(self, argv, threads):
        """argv under `taskset -c CPU` for one-thread runs when --pin is on: both sides of a row
        then run on the same CPU (on a VM the CPUs can differ by a third in speed, and a fresh
        process lands on either)."""
        if threads != 1 or self.args.pin is None:
            return argv
        return ["taskset", "-c", str(self.args.pin)] + argv

    def hapsyn_run(self, problem_path, threads, name, sets=()):
        """Runs hapsyn; returns (result.json, wall seconds)."""
        out = os.path.join(self.work, name)
        argv = self.pinned([self.hapsyn, "run", problem_path, "--threads", str(threads), "--out", out, "--quiet",
                            "--force"], threads)
        for s in sets:
            argv += ["--set", s]
        attempts = 5
        for attempt in range(attempts):  # the build may be relinked under us: retry a minute later
            t0 = time.perf_counter()
            p = subprocess.run(argv, capture_output=True, text=True)
            wall = time.perf_counter() - t0
            if p.returncode == 0:
                break
            if attempt == attempts - 1:
                sys.exit(f"failed (exit {p.returncode}): {' '.join(argv)}\n{p.stderr[-3000:]}")
            print(f"  hapsyn failed (exit {p.returncode}: {p.stderr.strip()[-300:]}); retrying in 60 s",
                  file=sys.stderr, flush=True)
            time.sleep(60)
        with open(os.path.join(out, "result.json")) as f:
            result = json.load(f)
        self.headers.setdefault("hapsyn", result.get("hapsyn"))
        self.headers.setdefault("machine", result.get("machine"))
        return result, wall, argv

    def peer(self, *argv, threads=0):
        full = self.pinned([self.python, PEERS] + list(argv), threads)
        p = subprocess.run(full, capture_output=True, text=True)
        if p.returncode not in (0, 1) or not p.stdout.strip():
            sys.exit(f"failed: {' '.join(full)}\n{p.stderr[-3000:]}")
        return json.loads(p.stdout.strip().splitlines()[-1]), full


def grid_copy(runner, prune):
    with open(os.path.join(ROOT, GRID)) as f:
        problem = json.load(f)
    problem = copy.deepcopy(problem)
    problem["solver"].setdefault("options", {})["prune"] = prune
    problem["name"] += "-prune" if prune else "-noprune"
    path = os.path.join(runner.work, f"fivebar-gii-coarse-prune-{str(prune).lower()}.json")
    with open(path, "w") as f:
        json.dump(problem, f, indent=1)
    return path


def solve_seconds(result):
    return result["phases"]["solve_s"]


def row_grid(runner, report, table):
    for prune in (False, True):
        path = grid_copy(runner, prune)
        for threads in (1, 2):
            wait_quiet(runner.args, f"grid prune={prune} threads={threads}")
            before = load()
            runs = []
            for i in range(runner.args.repeats):
                result, wall, argv = runner.hapsyn_run(path, threads, f"grid-{prune}-{threads}-{i}")
                runs.append(solve_seconds(result))
            result_path = os.path.join(runner.work, f"grid-{prune}-{threads}-0", "result.json")
            peer_args = ["numba-grid", "--threads", str(threads), "--repeats", str(runner.args.repeats),
                         "--check", result_path] + (["--prune"] if prune else [])
            peer, peer_argv = runner.peer(*peer_args, threads=threads)
            after = load()
            h = min(runs)
            label = f"10 mm GII grid, {'pruned' if prune else 'unpruned'}, {threads} thread{'s' if threads > 1 else ''}"
            entry = {
                "row": label, "kind": "grid", "prune": prune, "threads": threads,
                "hapsyn": {"command": " ".join(argv), "solve_s": h, "runs_solve_s": runs, "wall_s_last": wall,
                           "best": result["best"], "statistics": result["statistics"],
                           "evaluations": result["evaluations"], "seed": result["seed"]},
                "peer": peer, "peer_command": " ".join(peer_argv), "ratio": h / peer["seconds"],
                "load_before": before, "load_after": after, "resolved_problem": result["problem"],
            }
            report["rows"].append(entry)
            check = peer.get("check", {})
            table.append((label, h, f"numba prange ({threads})", peer["seconds"], h / peer["seconds"],
                          f"GII hapsyn {result['best']['score']:.12g}, numba {peer['best_value']:.12g}; optimum "
                          f"check {'passed' if check.get('passed') else 'FAILED'}; load {before[0]}-{after[0]}"))
            print(f"  {label}: hapsyn {h:.4f} s, numba {peer['seconds']:.4f} s", file=sys.stderr, flush=True)


def row_nsga2(runner, report, table):
    sets = ['indicators={"reference_point": [0.0, 0.0]}']
    with open(os.path.join(ROOT, NSGA2)) as f:
        problem = json.load(f)
    options = problem["solver"]["options"]
    seed = problem.get("seed", 1)
    hapsyn_rows = []
    for threads in (2, 1):
        wait_quiet(runner.args, f"hapsyn NSGA-II threads={threads}")
        before = load()
        result, wall, argv = runner.hapsyn_run(os.path.join(ROOT, NSGA2), threads, f"nsga2-{threads}", sets)
        after = load()
        front = [p["objectives"] for p in result.get("front", [])]
        hapsyn_rows.append((threads, result, wall, argv, before, after, front))
        print(f"  NSGA-II hapsyn {threads} threads: {solve_seconds(result):.2f} s", file=sys.stderr, flush=True)
    wait_quiet(runner.args, "DEAP NSGA-II")
    before = load()
    front_file = os.path.join(runner.work, "deap-front.json")
    peer, peer_argv = runner.peer("deap-nsga2", "--population", str(options["population"]), "--generations",
                                  str(options["generations"]), "--seed", str(seed), "--threads", "2",
                                  "--front-out", front_file)
    after = load()
    print(f"  NSGA-II DEAP: {peer['seconds']:.2f} s", file=sys.stderr, flush=True)
    sys.path.insert(0, os.path.dirname(PEERS))
    from fivebar_peers import hypervolume_2d
    for threads, result, wall, argv, b, a, front in hapsyn_rows:
        points = [[o["gii"], o["gdi"]] if isinstance(o, dict) else o for o in front]
        hv = result.get("indicators", {}).get("hypervolume")
        label = f"NSGA-II pop {options['population']} x {options['generations']} gen, {threads} thread{'s' if threads > 1 else ''}"
        entry = {
            "row": label, "kind": "nsga2", "threads": threads,
            "hapsyn": {"command": " ".join(argv), "solve_s": solve_seconds(result), "wall_s": wall,
                       "hypervolume": hv, "hypervolume_recomputed": hypervolume_2d(points),
                       "front_points": len(points), "evaluations": result["evaluations"],
                       "statistics": result["statistics"], "seed": result["seed"]},
            "peer": peer, "peer_command": " ".join(peer_argv), "ratio": solve_seconds(result) / peer["seconds"],
            "load_before": b, "load_after": a, "peer_load": [before, after], "resolved_problem": result["problem"],
        }
        report["rows"].append(entry)
        table.append((label, solve_seconds(result), "DEAP selNSGA2 + numba batch (2)", peer["seconds"],
                      solve_seconds(result) / peer["seconds"],
                      f"hypervolume hapsyn {hv:.6f} ({len(points)} points), DEAP {peer['hypervolume']:.6f} "
                      f"({peer['front_points']} points); seed {result['seed']}; load {b[0]}-{a[0]}"))


def row_numpy(runner, report, table):
    # The optimum check needs a hapsyn result of the same grid: a pruned 2-thread run (fast).
    result, _, argv = runner.hapsyn_run(grid_copy(runner, True), 2, "numpy-reference")
    wait_quiet(runner.args, "numpy grid")
    before = load()
    # Best of --paper-repeats runs, each a fresh process timing its own search (as the culling rows
    # it is the reference of).
    runs = [runner.peer("numpy-grid", "--check", os.path.join(runner.work, "numpy-reference", "result.json"),
                        threads=1) for _ in range(runner.args.paper_repeats)]
    after = load()
    peer, peer_argv = min(runs, key=lambda run: run[0]["seconds"])
    peer["all_seconds"] = [run[0]["seconds"] for run in runs]
    report["numpy_seconds"] = peer["seconds"]
    report["rows"].append({"row": "numpy 10 mm exhaustive GII search, 1 core", "kind": "numpy", "peer": peer,
                           "peer_command": " ".join(peer_argv), "load_before": before, "load_after": after,
                           "check_reference": {"command": " ".join(argv), "best": result["best"]}})
    check = peer.get("check", {})
    table.append(("numpy 10 mm exhaustive GII search (reference)", None, "numpy, 1 core", peer["seconds"], None,
                  f"GII {peer['best_value']:.9f}; optimum check {'passed' if check.get('passed') else 'FAILED'}; "
                  f"load {before[0]}-{after[0]}"))
    print(f"  numpy grid: {peer['seconds']:.2f} s", file=sys.stderr, flush=True)


def row_paper(runner, report, table):
    numpy_s = report.get("numpy_seconds")
    # Each study with block bounds (the default) and without them (the previous version's sweep),
    # in the same run: the baseline of the block bounds' gain.
    variants = [("", []), (", no block bounds", ["solver.options.block_bounds=false"])]
    for (base_label, problem), (suffix, sets) in [(p, v) for p in PAPER for v in variants]:
        label = base_label + suffix
        wait_quiet(runner.args, label)
        before = load()
        # Best of --paper-repeats runs, as the NumPy reference.
        runs = [runner.hapsyn_run(os.path.join(ROOT, problem), 2,
                                  os.path.basename(problem)[:-5] + ("-noblock" if sets else "") + f"-{i}", sets)
                for i in range(runner.args.paper_repeats)]
        after = load()
        result, wall, argv = min(runs, key=lambda run: solve_seconds(run[0]))
        s = solve_seconds(result)
        entry = {"row": label, "kind": "paper", "threads": 2,
                 "hapsyn": {"command": " ".join(argv), "solve_s": s, "wall_s": wall, "best": result.get("best"),
                            "statistics": result["statistics"], "evaluations": result["evaluations"],
                            "seed": result["seed"]},
                 "all_solve_s": [solve_seconds(run[0]) for run in runs],
                 "ratio_vs_numpy": s / numpy_s if numpy_s else None, "load_before": before, "load_after": after,
                 "resolved_problem": result["problem"]}
        report["rows"].append(entry)
        best = result.get("best", {}).get("score")
        table.append((label + ", 2 threads", s, "numpy 10 mm search", numpy_s, s / numpy_s if numpy_s else None,
                      f"best {best:.6f}; load {before[0]}-{after[0]}"))
        print(f"  {label}: {s:.2f} s", file=sys.stderr, flush=True)


def markdown(table):
    lines = ["| study | hapsyn s | peer | peer s | hapsyn / peer | notes |", "|---|---:|---|---:|---:|---|"]
    for label, h, peer, p, ratio, notes in table:
        lines.append(f"| {label} | {'' if h is None else f'{h:.4g}'} | {peer} | {'' if p is None else f'{p:.4g}'} | "
                     f"{'' if ratio is None else f'{ratio:.3g}'} | {notes} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hapsyn", default=os.environ.get("HAPSYN") or os.path.join(ROOT, "build", "bin", "hapsyn"))
    ap.add_argument("--only", help="comma-separated rows: " + ",".join(ROWS))
    ap.add_argument("--skip-paper", action="store_true", help="leave out the paper-resolution culling rows")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs of each grid row (best reported), both sides")
    ap.add_argument("--paper-repeats", type=int, default=3,
                    help="runs of the NumPy search and of each paper culling study (best reported, both sides)")
    ap.add_argument("--out", help="write every figure here (JSON)")
    ap.add_argument("--wait-load", type=float, default=0.0, metavar="LOAD",
                    help="before each row, wait until the 1-minute load average is below LOAD (0: do not wait)")
    ap.add_argument("--wait-max", type=float, default=900.0, metavar="S", help="longest wait per row [s]")
    ap.add_argument("--pin", type=int, default=max(os.sched_getaffinity(0)), metavar="CPU",
                    help="run the one-thread rows (hapsyn, numba, numpy) on this CPU (default: the highest one; "
                         "on the VM seen here CPU 0 was the slower one); --no-pin lets the OS place them")
    ap.add_argument("--no-pin", dest="pin", action="store_const", const=None)
    args = ap.parse_args()
    for name in ("repeats", "paper_repeats"):
        if getattr(args, name) < 1:
            sys.exit(f"--{name.replace('_', '-')} {getattr(args, name)}: must be at least 1")
    if args.pin is not None and args.pin not in os.sched_getaffinity(0):
        sys.exit(f"--pin {args.pin}: not a CPU this process may run on ({sorted(os.sched_getaffinity(0))})")
    if not os.path.isfile(args.hapsyn):
        sys.exit(f"no hapsyn binary at {args.hapsyn}: pass --hapsyn PATH or set HAPSYN")
    only = set(args.only.split(",")) if args.only else set(ROWS)
    unknown = only - set(ROWS)
    if unknown:
        sys.exit(f"--only: unknown rows {sorted(unknown)}; known: {', '.join(ROWS)}")
    if args.skip_paper:
        only.discard("paper")
    if "paper" in only:
        only.add("numpy")  # its ratio's reference
    runner = Runner(args)
    binary_root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(args.hapsyn))))
    version = subprocess.run([args.hapsyn, "--version"], capture_output=True, text=True).stdout.strip()
    report = {
        "benchmark": "fivebar_speed", "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
        "hapsyn_binary": os.path.abspath(args.hapsyn), "hapsyn_version": version,
        "git_describe": {"benchmarks": git_describe(ROOT), "binary_tree": git_describe(binary_root)},
        "machine": machine(), "repeats": args.repeats, "wait_load": args.wait_load, "pinned_cpu": args.pin,
        "load_start": load(),
        "uptime_start": subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip(),
        "python": sys.executable, "rows": [],
    }
    table = []
    print(f"hapsyn {version} ({report['git_describe']['binary_tree']}), {report['machine']['model_name']}, "
          f"{report['machine']['cpus']} CPUs; load {report['load_start']}", file=sys.stderr, flush=True)
    for name, fn in (("grid", row_grid), ("nsga2", row_nsga2), ("numpy", row_numpy), ("paper", row_paper)):
        if name in only:
            fn(runner, report, table)
    report["hapsyn_result_header"] = runner.headers
    report["load_end"] = load()
    report["uptime_end"] = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    report["markdown"] = markdown(table)
    m = report["machine"]
    print(f"hapsyn {version}, git {report['git_describe']['binary_tree']}; {m['model_name']}, {m['cpus']} CPUs "
          f"(avx2 {m['avx2']}, avx512f {m['avx512f']}); {report['date']}; load {report['load_start']} -> "
          f"{report['load_end']}\n")
    print(report["markdown"])
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as f:
            json.dump(report, f, indent=1)
    shutil.rmtree(runner.work, ignore_errors=True)
    failed = [r["row"] for r in report["rows"] if not r.get("peer", {}).get("check", {"passed": True})["passed"]]
    if failed:
        print(f"\noptimum check FAILED: {failed}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
