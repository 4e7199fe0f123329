#!/usr/bin/env python3
"""A sweep's and a comparison's output directory in `hapsyn view`, in headless Chromium: the page
shows the batch's table (one row per run of sweep.json / row of compare.json) and a bar per run
of the chosen column that has a value, and draws the run it names (a sweep's last run, a
comparison's first study) at that run's best design, all checked against the files; `hapsyn
report` of the sweep embeds its table. A sweep
without runs or whose shown run is gone, and a compare.json that is no JSON, are refused with a
message naming the file.

Usage: view_batch_test.py HAPSYN SWEEP_PROBLEM COMPARE_PROBLEM_A COMPARE_PROBLEM_B WORK_DIR.
Exit 0 when every check passes.
"""
import json
import os
import shutil
import subprocess
import sys

from view_process import ViewProcess
from view_support import browser_missing, chromium, check, check_stops, finish, get_json, wait_state


def check_batch(driver, hapsyn, folder, kind, rows, shown_dir, column, values):
    """rows: the file's run count; shown_dir: the run drawn; values: the column's cells."""
    with open(os.path.join(shown_dir, "result.json")) as f:
        shown = json.load(f)
    with ViewProcess(hapsyn, folder) as view:
        get = lambda route: get_json(view.url.rstrip("/") + route, timeout=30)
        batch, study = get("/api/result")["batch"], get("/api/study")
        check(batch["kind"] == kind and len(batch["rows"]) == rows, f"{kind}: /api/result batch of {len(batch['rows'])} rows = {rows}")
        check(study["design"] == shown["best"]["design"], f"{kind}: the 3D view shows {os.path.basename(shown_dir)}'s best design")
        driver.get(view.url)
        state = wait_state(driver, "ready")
        check(state.get("ready") is True and not state.get("error"), f"{kind}: page ready (error: {state.get('error')})")
        check(state.get("batchKind") == kind and state.get("batchRows") == rows, f"{kind}: batchRows {state.get('batchRows')} = {rows}")
        check(state.get("batchColumn") == column, f"{kind}: plots {state.get('batchColumn')} = {column}")
        bars = sum(1 for v in values if v is not None)
        check(state.get("batchBars") == bars, f"{kind}: {state.get('batchBars')} bars = {bars} runs with a {column}")
        table_rows = driver.execute_script("return document.querySelectorAll('#batch-table tbody tr').length")
        check(table_rows == rows, f"{kind}: {table_rows} table rows")
        driver.save_screenshot(os.path.join(os.path.dirname(folder), f"view-{kind}.png"))
        check_stops(view, f"{kind}: the server stops with exit 0")


def check_errors(hapsyn, sweep, work):
    empty = os.path.join(work, "sweep-no-runs")
    shutil.rmtree(empty, ignore_errors=True)
    os.makedirs(empty)
    with open(os.path.join(sweep, "sweep.json")) as f:
        doc = json.load(f)
    with open(os.path.join(empty, "sweep.json"), "w") as f:
        json.dump({**doc, "runs": []}, f)
    gone = os.path.join(work, "sweep-run-gone")
    shutil.rmtree(gone, ignore_errors=True)
    shutil.copytree(sweep, gone)
    last = doc["runs"][-1]["case"]
    shutil.rmtree(os.path.join(gone, last))
    broken = os.path.join(work, "compare-broken")
    shutil.rmtree(broken, ignore_errors=True)
    os.makedirs(broken)
    with open(os.path.join(broken, "compare.json"), "w") as f:
        f.write('{"rows": [')
    for folder, message in ((empty, f"view: {empty}/sweep.json: no \"runs\" to show (an unfinished sweep?)"),
                            (gone, f"{gone}/{last}/result.json"),
                            (broken, f"view: {broken}/compare.json")):
        r = subprocess.run([hapsyn, "view", folder, "--port", "0"], capture_output=True, text=True, timeout=120)
        check(r.returncode == 1 and message in r.stderr, f"{os.path.basename(folder)}: exit 1, '{message}' ({r.stderr.strip()})")


def main():
    hapsyn, sweep_problem, compare_a, compare_b, work = sys.argv[1:6]
    os.makedirs(work, exist_ok=True)
    if browser_missing():
        return 1
    sweep, compare = os.path.join(work, "sweep"), os.path.join(work, "compare")
    for folder in (sweep, compare):
        shutil.rmtree(folder, ignore_errors=True)
    subprocess.run([hapsyn, "sweep", sweep_problem, "--vary", "scene.options.step=0.02,0.01,0.005", "--out", sweep],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    subprocess.run([hapsyn, "compare", compare_a, compare_b, "--out", compare], check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    with open(os.path.join(sweep, "sweep.json")) as f:
        runs = json.load(f)["runs"]
    with open(os.path.join(compare, "compare.json")) as f:
        rows = json.load(f)["rows"]
    with chromium() as driver:
        driver.set_page_load_timeout(30)
        check_batch(driver, hapsyn, sweep, "sweep", len(runs), os.path.join(sweep, runs[-1]["case"]),
                    "errors.objective_error", [r["errors"].get("objective_error") for r in runs])
        check_batch(driver, hapsyn, compare, "compare", len(rows),
                    os.path.join(compare, os.path.basename(rows[0]["output_directory"])),
                    "wall_time_s", [r.get("wall_time_s") for r in rows])
    check_errors(hapsyn, sweep, work)
    r = subprocess.run([hapsyn, "report", sweep], capture_output=True, text=True, timeout=120)
    html = open(os.path.join(sweep, "report.html"), encoding="utf-8").read() if r.returncode == 0 else ""
    check('"kind":"sweep"' in html and html.count('"label":') >= len(runs), "hapsyn report of a sweep embeds its table")
    return finish()


if __name__ == "__main__":
    sys.exit(main())
