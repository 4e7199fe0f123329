"""Ctrl-C during Study.run() stops the solver gracefully (status "stopped")."""
import json
import os
import signal
import subprocess
import sys
import time

from conftest import PROBLEMS

CHILD = r"""
import json, sys, time
import hapsyn
study = hapsyn.load(sys.argv[1], set=["threads=2", "design.l0.step=0.002", "design.l1.step=0.002",
                                      "design.l2.step=0.002", "design.r.step=0.002"])
lines = []
print("running", flush=True)
t0 = time.monotonic()
result = study.run(progress=lines.append)
print(json.dumps({"status": result.status, "message": result.message, "seconds": time.monotonic() - t0,
                  "designs": result.info["evaluations"]["designs"]}), flush=True)
"""


def test_sigint_during_run_stops_with_status_stopped():
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(PROBLEMS / "fivebar-gii-coarse.json")],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=dict(os.environ))
    assert child.stdout.readline().strip() == "running"
    time.sleep(1.0)
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=120)
    stopped_after = time.monotonic() - sent
    assert child.returncode == 0, err
    report = json.loads(out.strip().splitlines()[-1])
    assert report["status"] == "stopped", report
    assert report["designs"] > 0
    assert stopped_after < 10, f"the run took {stopped_after:.1f} s to stop"


RESUME = r"""
import json, os, signal, sys, threading
import hapsyn
sets = ["threads=1", "solver.options.runs=2", "solver.options.population=16", "solver.options.generations=30000",
        "solver.options.stall_generations=100000"]
study = hapsyn.load(sys.argv[1], set=sets)
out, plain_out = sys.argv[2], sys.argv[3]
threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT)).start()  # Ctrl-C 0.3 s in (of about 3 s)
first = study.run(seed=5, out=out)
resumed = study.run(seed=5, out=out, resume=True)
plain = study.run(seed=5, out=plain_out)
print(json.dumps({"first": first.status, "message": first.message, "resumed": resumed.status,
                  "same": resumed.best_objectives == plain.best_objectives,
                  "best": resumed.best_objectives, "plain": plain.best_objectives}), flush=True)
"""


def test_a_stopped_run_resumes_from_python_to_the_uninterrupted_result(tmp_path):
    # The stopped run's message says "resume with --resume": Study.run(resume=True) does it.
    child = subprocess.run([sys.executable, "-c", RESUME, str(PROBLEMS / "fivebar-gii-ga-coarse.json"),
                            str(tmp_path / "stopped"), str(tmp_path / "plain")],
                           capture_output=True, text=True, timeout=600, env=dict(os.environ))
    assert child.returncode == 0, child.stderr
    report = json.loads(child.stdout.strip().splitlines()[-1])
    assert report["first"] == "stopped", report
    assert "resume" in report["message"], report
    assert report["resumed"] != "stopped", report
    assert report["same"], report
