#!/usr/bin/env python3
"""The virtual prototype's replay of a motion study (`hapsyn view`, /api/replay and the page in
headless Chromium), checked against what other code computes:
- the samples the page marks infeasible are exactly those whose motion_feasibility values in the
  samples.csv of `hapsyn run` are not all 1 (or that have none);
- /api/replay's joint values, |qdot|/limit and |tau|/limit equal those computed here with NumPy
  from the quantities the Python module's Study.evaluate(samples=True) returns (the mechanism's
  IK, joint rates, inertia, velocity torque and gravity), and its time stamps the scene's "time";
- the bars agree with the metric: a reachable sample is velocity (acceleration) feasible in
  samples.csv exactly when all its |qdot|/limit (|tau|/limit) are <= 1;
- the page scrubbed to a sample shows that sample's joint values and red bars where a ratio > 1;
  played at x4 its clock runs about four times real time;
- a study without a motion scene answers /api/replay with the reason.
Saves a screenshot.

Usage: view_replay_test.py HAPSYN PROBLEM_FILE NON_MOTION_PROBLEM WORK_DIR
(PYTHONPATH holds the build's python/ folder). Exit 0 when every check passes.
"""
import os
import sys
import time

from view_process import ViewProcess, read_csv_columns
from view_support import (browser_missing, chromium, check, check_stops, finish, get_json, run_study, screenshot,
                          wait_for)

FEASIBILITY = "motion_feasibility."


def close(a, b, tol):
    return abs(a - b) <= tol * max(1.0, abs(b))


def expected_from_csv(columns, rows):
    """Per sample: marked infeasible, and the velocity / acceleration flags (None when absent)."""
    checks = [c for c in columns if c.startswith(FEASIBILITY)]
    infeasible = set()
    for i in range(rows):
        cells = [columns[c][i] for c in checks]
        if any(v == "" for v in cells) or any(float(v) != 1.0 for v in cells):
            infeasible.add(i)
    def flag(name):
        col = FEASIBILITY + name
        return [None if v == "" else float(v) == 1.0 for v in columns[col]] if col in columns else None
    return checks, infeasible, flag("velocity_feasible"), flag("acceleration_feasible")


def independent_quantities(problem):
    """q, |qdot|/limit and |tau|/limit per sample from the Python module (NaN where unreachable)."""
    import numpy as np
    import hapsyn
    study = hapsyn.load(problem)
    names = ["joint_velocity", "max_velocity", "joint_acceleration", "inertia", "velocity_torque", "gravity", "max_torque"]
    r = study.evaluate({}, samples=True, quantities=names)  # the shipped study fixes every variable
    qs = r["quantities"]
    q = np.asarray(qs["q"])
    qdot_ratio = np.abs(qs["joint_velocity"]) / qs["max_velocity"]
    tau = np.einsum("nij,nj->ni", qs["inertia"], qs["joint_acceleration"]) + qs["velocity_torque"] + qs["gravity"]
    tau_ratio = np.abs(tau) / qs["max_torque"]
    time_stamps = np.asarray(study.scene.attributes["time"]).reshape(-1)
    return q, qdot_ratio, tau_ratio, time_stamps, list(r["sample_status"])


def main():
    hapsyn, problem, other, work = sys.argv[1:5]
    os.makedirs(work, exist_ok=True)
    if browser_missing():
        return 1
    out = os.path.join(work, "run")
    run_study(hapsyn, problem, out)
    columns, rows = read_csv_columns(os.path.join(out, "samples.csv"))
    checks, infeasible, velocity_ok, acceleration_ok = expected_from_csv(columns, rows)
    check(len(checks) > 0, f"samples.csv has motion_feasibility columns {checks}")
    print(f"     {len(infeasible)} of {rows} samples infeasible in samples.csv", flush=True)
    q_ref, qdot_ref, tau_ref, time_ref, status_ref = independent_quantities(problem)

    with ViewProcess(hapsyn, other) as view:
        doc = get_json(view.url + "api/replay")
        check(doc.get("available") is False and "only a motion scene's study can be replayed" in doc.get("reason", ""),
              f"a study without a motion scene: /api/replay says why ({doc.get('reason')})")
        view.stop()

    with ViewProcess(hapsyn, problem) as view:
        doc = get_json(view.url + "api/replay")
        n, J = doc["frames"], doc["joints"]
        check(doc["available"] and n == rows and sorted(doc["sample"]) == list(range(rows)),
              f"/api/replay: {n} frames, one per sample ({rows})")
        check(doc["checks"] == checks, f"/api/replay checks {doc['checks']} = samples.csv's motion_feasibility columns")
        marked = {doc["sample"][f] for f in range(n) if doc["feasible"][f] == 0}
        check(marked == infeasible, f"/api/replay marks the {len(marked)} samples samples.csv marks infeasible")
        ordered = all(doc["trajectory"][f] < doc["trajectory"][f + 1] or
                      (doc["trajectory"][f] == doc["trajectory"][f + 1] and doc["time"][f] < doc["time"][f + 1])
                      for f in range(n - 1))
        check(ordered, "frames are time-ordered within each trajectory")
        bad_time = [f for f in range(n) if doc["time"][f] != time_ref[doc["sample"][f]]]
        check(not bad_time, f"time stamps = the scene's time attribute ({len(bad_time)} differ)")
        bad_q, bad_ratio, bad_flags, reachable = [], [], [], 0
        for f in range(n):
            i = doc["sample"][f]
            if doc["status"][f] != status_ref[i]:
                bad_q.append(f)
                continue
            if status_ref[i] != "reachable":
                if any(v is not None for v in doc["q"][f * J:f * J + J]):
                    bad_q.append(f)
                continue
            reachable += 1
            q = doc["q"][f * J:f * J + J]
            qd = doc["qdot_ratio"][f * J:f * J + J]
            tau = doc["tau_ratio"][f * J:f * J + J]
            if any(not close(q[j], q_ref[i][j], 1e-12) for j in range(J)):
                bad_q.append(f)
            if any(not close(qd[j], qdot_ref[i][j], 1e-9) or not close(tau[j], tau_ref[i][j], 1e-9) for j in range(J)):
                bad_ratio.append(f)
            if velocity_ok is not None and velocity_ok[i] != all(v <= 1.0 for v in qd):
                bad_flags.append(f)
            if acceleration_ok is not None and acceleration_ok[i] != all(v <= 1.0 for v in tau):
                bad_flags.append(f)
        check(reachable > 0 and not bad_q, f"joint values and statuses = the Python module's IK ({len(bad_q)} of {n} differ)")
        check(not bad_ratio, f"|qdot|/limit, |tau|/limit = NumPy's from the module's quantities ({len(bad_ratio)} differ)")
        check(not bad_flags, f"the bars agree with samples.csv's velocity / acceleration flags ({len(bad_flags)} differ)")

        with chromium() as driver:
            driver.set_page_load_timeout(60)
            driver.get(view.url)
            state = wait_for(driver, lambda replay: replay.get("ready"), 90, poll=0.3, script=(
                "const r = (window.hapsynView || {}).replay || {};"
                "return {ready: r.ready, available: r.available, error: r.error, frames: r.frames};"))
            check(state.get("ready") and state.get("available") and not state.get("error"),
                  f"the page's replay is ready ({state})")
            page_marked = driver.execute_script("return window.hapsynView.replay.infeasible")
            check(set(page_marked) == infeasible and len(page_marked) == len(infeasible),
                  f"the page marks exactly the {len(infeasible)} samples samples.csv marks infeasible")
            reachable_infeasible = [i for i in sorted(infeasible) if status_ref[i] == "reachable"]
            feasible = [i for i in range(rows) if i not in infeasible]
            picks = [p for p in (reachable_infeasible[:1] + feasible[:1] + feasible[-1:]) if p is not None]
            for sample in picks:
                driver.execute_script("window.hapsynView.replay.seekSample(arguments[0])", sample)
                time.sleep(0.2)
                shown = driver.execute_script(
                    "const r = window.hapsynView.replay; return {sample: r.sample, q: r.q, qdot: r.qdotRatio, tau: r.tauRatio,"
                    " red: document.querySelectorAll('#proto-bars .fill.over').length,"
                    " scrubber: Number(document.getElementById('proto-scrubber').value), frame: r.frame};")
                expected_red = sum(1 for v in list(qdot_ref[sample]) + list(tau_ref[sample]) if v > 1.0)
                check(shown["sample"] == sample and all(close(shown["q"][j], q_ref[sample][j], 1e-12) for j in range(J)),
                      f"scrubbed to sample {sample}: joint values {['%.4f' % v for v in shown['q']]} = the IK's")
                check(shown["red"] == expected_red and shown["scrubber"] == shown["frame"],
                      f"sample {sample}: {shown['red']} red bars = ratios > 1 ({expected_red}); scrubber at the frame")
            # x4: the replay's clock runs four times the page's own clock while it plays
            # (wallPlayed, the sum of the frame intervals it advanced by), checked exactly, and
            # never ahead of real time; played until it moved 1 s (a loaded machine's frames come late).
            first = doc["sample"][0]
            begin = driver.execute_script("const r = window.hapsynView.replay; r.seekSample(arguments[0]); r.setSpeed(4);"
                                          " const c = r.clock; r.play(); return c;", first)
            start = time.time()
            moved = 0.0
            while time.time() - start < 30 and moved < 1.0:
                time.sleep(0.2)
                moved = driver.execute_script("return window.hapsynView.replay.clock;") - begin
            played = driver.execute_script("const r = window.hapsynView.replay; r.pause(); return [r.clock, r.wallPlayed];")
            elapsed = time.time() - start
            moved, wall = played[0] - begin, played[1]
            check(moved >= 1.0 and abs(moved - 4.0 * wall) <= 1e-6 * max(1.0, moved) and wall <= elapsed + 0.1,
                  f"x4: the replay moved {moved:.3f} s in {wall:.3f} s of the page's clock ({elapsed:.2f} s real)")
            screenshot(driver, os.path.join(work, "replay-" + os.path.splitext(os.path.basename(problem))[0] + ".png"))
        check_stops(view)
    return finish()


if __name__ == "__main__":
    sys.exit(main())
