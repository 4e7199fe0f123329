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
