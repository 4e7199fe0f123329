#!/usr/bin/env python3
"""hapsyn on MPI ranks and as SLURM shards, end to end (README: "Clusters").

Three parts, each a ctest entry (tests/CMakeLists.txt):

results  Every problem in tests/mpi/problems/ runs as one process (2 threads) and under
         `mpirun -n N` (N = 1, 2, 3; 1 thread each, oversubscribed); result.json's status, best
         and front must be identical. For solvers that can be sharded (grid, culling, ga) the
         three shares of `--shard i/3` merged with `hapsyn merge` must give the same again.
faults   A distributed grid search that a signal stops (SIGUSR1 to mpirun: exit 4, status
         stopped), whose rank 1 is killed (SIGKILL: the job ends within a bound, naming the
         rank), whose rank 2 hangs (SIGSTOP: rank 0 ends the job after --rank-timeout, naming
         rank and host); each time `--resume` on another number of ranks completes it with the
         single-process result.
input    Bad input: --shard 3/2, 0/0, a solver that cannot be sharded, --shard under mpirun, and
         `hapsyn merge` of shares of different problems or seeds, a missing, a repeated, an
         unfinished share and a directory that holds no share: clear errors naming the rule.
         Then docs/slurm/array.sbatch (3 array tasks) and merge.sbatch run as SLURM runs them
         (its environment variables, hapsyn on PATH): the merged result equals one process.

Exit status 0 when every check passed; each failure is printed with the command and its output.
"""
import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import time

SHARDABLE = {"grid", "culling", "ga"}
FAILURES = []


def fail(what, detail=""):
    FAILURES.append(what)
    print(f"FAIL: {what}\n{detail}", flush=True)


def ok(what):
    print(f"ok: {what}", flush=True)


class Runner:
    def __init__(self, args):
        self.hapsyn = os.path.abspath(args.hapsyn)
        self.mpiexec = args.mpiexec
        self.work = os.path.abspath(args.work)
        self.env = dict(os.environ)
        # Open MPI refuses root unless told; CI runs as root.
        self.env.update({"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
                         "OMPI_MCA_rmaps_base_oversubscribe": "1"})
        for k in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"):
            self.env.pop(k, None)

    def out(self, name):
        path = os.path.join(self.work, name)
        shutil.rmtree(path, ignore_errors=True)
        return path

    def mpi(self, n):
        return [self.mpiexec, "--oversubscribe", "-n", str(n)]

    def run(self, argv, timeout=300):
        """Runs argv; returns (exit code, stdout, stderr)."""
        p = subprocess.run(argv, env=self.env, capture_output=True, text=True, timeout=timeout)
        return p.returncode, p.stdout, p.stderr

    def start(self, argv):
        return subprocess.Popen(argv, env=self.env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                start_new_session=True)


def result_of(directory):
    with open(os.path.join(directory, "result.json")) as f:
        return json.load(f)


def essence(result):
    """What must not depend on the number of ranks or shares."""
    return {"status": result["status"], "best": result.get("best"), "front": result.get("front")}


def same_result(what, reference, result):
    a, b = essence(reference), essence(result)
    if a == b:
        ok(what)
        return True
    fail(what, f"single process: {json.dumps(a)[:600]}\n         this: {json.dumps(b)[:600]}")
    return False


def run_checked(r, what, argv, expect=0, timeout=300):
    code, out, err = r.run(argv, timeout)
    if code != expect:
        fail(f"{what}: exit {code}, expected {expect}", f"$ {' '.join(argv)}\n{out[-2000:]}\n{err[-3000:]}")
        return False
    return True


# ---- results ----

def check_problem(r, problem):
    name = os.path.splitext(os.path.basename(problem))[0]
    single = r.out(f"{name}/single")
    if not run_checked(r, f"{name}: single process", [r.hapsyn, "run", problem, "--threads", "2", "--out", single, "--quiet"]):
        return
    reference = result_of(single)
    if reference["status"] not in ("converged", "budget_exhausted"):
        fail(f"{name}: the single-process run must finish (status {reference['status']}: {reference['message']})")
        return
    for n in (1, 2, 3):
        out = r.out(f"{name}/mpi-{n}")
        if run_checked(r, f"{name}: mpirun -n {n}",
                       r.mpi(n) + [r.hapsyn, "run", problem, "--threads", "1", "--out", out, "--quiet"]):
            result = result_of(out)
            same_result(f"{name}: mpirun -n {n} equals one process", reference, result)
            if n > 1 and result.get("ranks", {}).get("count") != n:
                fail(f"{name}: result.json of mpirun -n {n} must record the ranks", json.dumps(result.get("ranks")))
    if reference["problem"]["solver"]["plugin"] in SHARDABLE:
        shards = []
        for i in (1, 2, 3):
            out = r.out(f"{name}/shard-{i}")
            shards.append(out)
            if not run_checked(r, f"{name}: --shard {i}/3",
                               [r.hapsyn, "run", problem, "--threads", "1", "--shard", f"{i}/3", "--out", out, "--quiet"]):
                return
        merged = r.out(f"{name}/merged")
        if run_checked(r, f"{name}: merge", [r.hapsyn, "merge", shards[2], shards[0], shards[1], "--out", merged, "--quiet"]):
            same_result(f"{name}: 3 shares merged equal one process", reference, result_of(merged))


def sweep_rows(directory):
    """sweep.json's rows without what depends on timing or reuse."""
    with open(os.path.join(directory, "sweep.json")) as f:
        doc = json.load(f)
    keep = ("case", "values", "objectives", "errors", "status")
    return {"status": doc["status"], "runs": [{k: row.get(k) for k in keep} for row in doc["runs"]]}


def check_sweep(r, problem):
    """hapsyn sweep: its cases over ranks and as 3 merged shares equal one process."""
    vary = ["--vary", "scene.options.step=0.05,0.025,0.02", "--vary", "solver.options.prune=true,false"]
    single = r.out("sweep/single")
    if not run_checked(r, "sweep: single process", [r.hapsyn, "sweep", problem, "--threads", "1", "--out", single] + vary):
        return
    reference = sweep_rows(single)
    for n in (2, 3):
        out = r.out(f"sweep/mpi-{n}")
        if run_checked(r, f"sweep: mpirun -n {n}", r.mpi(n) + [r.hapsyn, "sweep", problem, "--threads", "1", "--out", out] + vary):
            if sweep_rows(out) == reference:
                ok(f"sweep: mpirun -n {n} gives the rows of one process")
            else:
                fail(f"sweep: mpirun -n {n} differs", f"{json.dumps(reference)[:800]}\n{json.dumps(sweep_rows(out))[:800]}")
    shards = []
    for i in (1, 2, 3):
        out = r.out(f"sweep/shard-{i}")
        shards.append(out)
        if not run_checked(r, f"sweep: --shard {i}/3", [r.hapsyn, "sweep", problem, "--threads", "1", "--shard", f"{i}/3",
                                                        "--out", out] + vary):
            return
    merged = r.out("sweep/merged")
    if run_checked(r, "sweep: merge", [r.hapsyn, "merge"] + shards + ["--out", merged]):
        if sweep_rows(merged) == reference:
            ok("sweep: 3 shares merged give the rows of one process")
        else:
            fail("sweep: 3 merged shares differ", f"{json.dumps(reference)[:800]}\n{json.dumps(sweep_rows(merged))[:800]}")


def part_results(r, problems_dir):
    problems = sorted(os.path.join(problems_dir, f) for f in os.listdir(problems_dir) if f.endswith(".json"))
    if not problems:
        fail(f"no problem files in {problems_dir}")
    for p in problems:
        check_problem(r, p)
    check_sweep(r, os.path.join(problems_dir, "grid-best.json"))


# ---- faults ----

def rank_pids(mpirun_pid):
    """{rank: pid} of the hapsyn processes mpirun started (read from their environment)."""
    ranks = {}
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open(f"/proc/{pid}/environ", "rb") as f:
                env = dict(kv.split(b"=", 1) for kv in f.read().split(b"\0") if b"=" in kv)
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                cmd = f.read()
        except OSError:
            continue
        if b"hapsyn" in cmd and b"OMPI_COMM_WORLD_RANK" in env and int(pid) != mpirun_pid:
            ranks[int(env[b"OMPI_COMM_WORLD_RANK"])] = int(pid)
    return ranks


def wait_for_checkpoint(out, job, seconds=60):
    deadline = time.time() + seconds
    while time.time() < deadline and job.poll() is None:
        if os.path.exists(os.path.join(out, "checkpoint.json")):
            return True
        time.sleep(0.1)
    return False


def fault_case(r, name, problem, sets, reference, n, act, expect_code, expect_text, resume_ranks, bound_s):
    out = r.out(f"faults/{name}")
    argv = r.mpi(n) + [r.hapsyn, "run", problem, "--threads", "1", "--out", out, "--quiet", "--rank-timeout", "4"] + sets
    job = r.start(argv)
    if not wait_for_checkpoint(out, job):
        job.kill()
        fail(f"{name}: no checkpoint appeared (is the study long enough?)", job.communicate()[1][-2000:])
        return
    ranks = rank_pids(job.pid)
    if job.poll() is not None or len(ranks) != n:
        fail(f"{name}: the job ended (or its ranks were not found: {sorted(ranks)}) before the fault: make the study "
             f"longer", job.communicate()[1][-2000:] if job.poll() is not None else "")
        job.kill()
        return
    t0 = time.time()
    act(job, ranks)
    try:
        stdout, stderr = job.communicate(timeout=bound_s)
    except subprocess.TimeoutExpired:
        os.killpg(job.pid, signal.SIGKILL)
        for pid in ranks.values():
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        fail(f"{name}: the job did not end within {bound_s} s")
        return
    took = time.time() - t0
    for pid in ranks.values():  # a stopped rank mpirun could not end
        try:
            os.kill(pid, signal.SIGCONT)
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
    if (expect_code == 0 and job.returncode != 0) or (expect_code != 0 and job.returncode == 0) or \
            (expect_code > 0 and job.returncode != expect_code):
        fail(f"{name}: exit {job.returncode}, expected {'non-zero' if expect_code < 0 else expect_code}", stderr[-3000:])
        return
    if expect_text and not all(t in stderr + stdout for t in expect_text):
        fail(f"{name}: the job's message must say {expect_text}", stderr[-3000:])
        return
    ok(f"{name}: the job ended in {took:.1f} s (exit {job.returncode})")
    resume = (r.mpi(resume_ranks) if resume_ranks > 0 else []) + [
        r.hapsyn, "run", problem, "--threads", "1", "--out", out, "--quiet", "--resume"] + sets
    if run_checked(r, f"{name}: --resume on {max(resume_ranks, 1)} rank(s)", resume):
        same_result(f"{name}: resumed on {max(resume_ranks, 1)} rank(s) equals one uninterrupted process", reference,
                    result_of(out))


def part_faults(r, problem, sets):
    single = r.out("faults/single")
    if not run_checked(r, "faults: single process", [r.hapsyn, "run", problem, "--threads", "2", "--out", single, "--quiet"] + sets):
        return
    reference = result_of(single)

    def usr1(job, ranks):
        os.kill(job.pid, signal.SIGUSR1)

    def kill_rank1(job, ranks):
        os.kill(ranks[1], signal.SIGKILL)

    def stop_rank2(job, ranks):
        os.kill(ranks[2], signal.SIGSTOP)

    fault_case(r, "stop", problem, sets, reference, 3, usr1, 4, ["stopped"], 2, 60)
    fault_case(r, "kill", problem, sets, reference, 3, kill_rank1, -1, ["rank 1"], 2, 60)
    fault_case(r, "hang", problem, sets, reference, 3, stop_rank2, -1, ["rank 2 on", "has not answered"], 0, 60)


# ---- input ----

def expect_refusal(r, what, argv, fragments):
    code, out, err = r.run(argv, 120)
    if code == 0 or not all(f in err for f in fragments):
        fail(f"{what}: expected a non-zero exit and a message with {fragments}", f"$ {' '.join(argv)}\nexit {code}\n{err[-2000:]}")
    else:
        ok(what)


def part_input(r, grid_problem, other_problem):
    h = r.hapsyn
    expect_refusal(r, "--shard 3/2", [h, "run", grid_problem, "--shard", "3/2", "--out", r.out("in/a")],
                   ["--shard 3/2", "must lie in 1..N (N = 2)"])
    expect_refusal(r, "--shard 0/0", [h, "run", grid_problem, "--shard", "0/0", "--out", r.out("in/a")],
                   ["--shard 0/0", "N must be >= 1"])
    expect_refusal(r, "--shard for a solver that cannot be sharded",
                   [h, "run", other_problem, "--shard", "1/2", "--out", r.out("in/a")], ["cannot be split into shares"])
    expect_refusal(r, "--shard under mpirun", r.mpi(2) + [h, "run", grid_problem, "--shard", "1/2", "--out", r.out("in/a")],
                   ["use either mpirun or --shard"])
    # Shares to merge: 1/2 and 2/2 of one run, and shares of other problems and seeds.
    dirs = {}
    for key, extra in (("a1", ["--shard", "1/2"]), ("a2", ["--shard", "2/2"]),
                       ("seed", ["--shard", "2/2", "--seed", "99"]),
                       ("other", ["--shard", "2/2", "--set", "solver.options.progress_interval=3"]),
                       ("whole", [])):
        dirs[key] = r.out(f"in/{key}")
        if not run_checked(r, f"input: run share {key}", [h, "run", grid_problem, "--threads", "1", "--quiet", "--out",
                                                          dirs[key]] + extra):
            return
    merge = [h, "merge", "--out", r.out("in/merged")]
    expect_refusal(r, "merge: a missing share", merge + [dirs["a1"]], ["shard 2/2 is missing (given: 1/2)"])
    expect_refusal(r, "merge: a share given twice", merge + [dirs["a1"], dirs["a1"], dirs["a2"]], ["given twice"])
    expect_refusal(r, "merge: shares of different seeds", merge + [dirs["a1"], dirs["seed"]], ["seed 99", "seed"])
    expect_refusal(r, "merge: shares of different problems", merge + [dirs["a1"], dirs["other"]],
                   ["a share of a different problem", "/solver/options/progress_interval"])
    expect_refusal(r, "merge: a directory without a share", merge + [dirs["a1"], dirs["whole"]], ["not a share's result"])
    expect_refusal(r, "merge: a directory without a result", merge + [dirs["a1"], r.out("in/empty")], ["no result.json"])
    # An unfinished share (as a signal leaves it): refused with the command that finishes it.
    unfinished = r.out("in/unfinished")
    shutil.copytree(dirs["a2"], unfinished)
    path = os.path.join(unfinished, "result.json")
    with open(path) as f:
        doc = json.load(f)
    doc["shard"]["complete"] = False
    with open(path, "w") as f:
        json.dump(doc, f)
    expect_refusal(r, "merge: an unfinished share", merge + [dirs["a1"], unfinished],
                   ["was stopped before it finished its share", "--shard 2/2", "--resume"])
    # A damaged checkpoint on resume under mpirun: every rank finds it, rank 0 alone says so (no abort).
    damaged = r.out("in/damaged")
    shutil.copytree(dirs["a1"], damaged)
    path = os.path.join(damaged, "checkpoint.json")
    with open(path) as f:
        doc = json.load(f)
    doc["seed"] = doc["seed"] + 1
    with open(path, "w") as f:
        json.dump(doc, f)
    code, out, err = r.run(r.mpi(2) + [h, "run", grid_problem, "--threads", "1", "--quiet", "--resume", "--out", damaged], 120)
    if code == 0 or err.count("damaged or edited") != 1 or "MPI_ABORT" in err:
        fail("resume of a damaged checkpoint on 2 ranks: one message, no abort", f"exit {code}\n{err[-2000:]}")
    else:
        ok("resume of a damaged checkpoint on 2 ranks: one message, no abort")


def part_slurm(r, problem, docs):
    """docs/slurm/array.sbatch (3 tasks) and merge.sbatch as SLURM runs them (its environment),
    with hapsyn on PATH: the merged result equals one process."""
    work = r.out("slurm")
    os.makedirs(work)
    bindir = os.path.join(work, "bin")
    os.makedirs(bindir)
    os.symlink(r.hapsyn, os.path.join(bindir, "hapsyn"))
    env = dict(r.env, PATH=bindir + os.pathsep + r.env.get("PATH", ""), SLURM_CPUS_PER_TASK="1",
               SLURM_ARRAY_TASK_COUNT="3", SLURM_ARRAY_JOB_ID="7")
    for task in range(3):
        e = dict(env, SLURM_ARRAY_TASK_ID=str(task))
        p = subprocess.run(["bash", os.path.join(docs, "array.sbatch"), problem], cwd=work, env=e, capture_output=True,
                           text=True, timeout=300)
        if p.returncode != 0:
            fail(f"slurm: array.sbatch task {task}: exit {p.returncode}", p.stderr[-2000:])
            return
    p = subprocess.run(["bash", os.path.join(docs, "merge.sbatch"), problem], cwd=work, env=env, capture_output=True,
                       text=True, timeout=300)
    if p.returncode != 0:
        fail(f"slurm: merge.sbatch: exit {p.returncode}", p.stderr[-2000:])
        return
    study = os.path.splitext(os.path.basename(problem))[0]
    single = r.out("slurm-single")
    if run_checked(r, "slurm: single process", [r.hapsyn, "run", problem, "--threads", "1", "--out", single, "--quiet"]):
        same_result("slurm: the job array's 3 shares merged by merge.sbatch equal one process", result_of(single),
                    result_of(os.path.join(work, "results", study)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hapsyn", required=True)
    ap.add_argument("--mpiexec", default="mpirun")
    ap.add_argument("--problems", required=True, help="folder of the results part's problem files")
    ap.add_argument("--fault-problem", help="a distributed study of some seconds (faults part)")
    ap.add_argument("--fault-set", action="append", default=[], help="--set for the fault problem")
    ap.add_argument("--other-problem", help="a study whose solver cannot be sharded (input part)")
    ap.add_argument("--work", required=True)
    ap.add_argument("--docs", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "docs", "slurm"),
                    help="folder of the sbatch examples (input part)")
    ap.add_argument("--part", choices=["results", "faults", "input"], required=True)
    args = ap.parse_args()
    r = Runner(args)
    os.makedirs(r.work, exist_ok=True)
    t0 = time.time()
    if args.part == "results":
        part_results(r, args.problems)
    elif args.part == "faults":
        part_faults(r, args.fault_problem, [x for s in args.fault_set for x in ("--set", s)])
    else:
        part_input(r, os.path.join(args.problems, "grid-best.json"), args.other_problem)
        part_slurm(r, os.path.join(args.problems, "grid-best.json"), args.docs)
    print(f"{args.part}: {len(FAILURES)} failure(s) in {time.time() - t0:.1f} s")
    return 1 if FAILURES else 0


if __name__ == "__main__":
    sys.exit(main())
