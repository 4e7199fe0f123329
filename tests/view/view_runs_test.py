#!/usr/bin/env python3
"""A GA result directory in `hapsyn view`, in headless Chromium: the convergence plot has one line
per run with one point per generation of that run's history where it has a best score, and the
runs' and clusters' tables one row per run and per cluster, all counted here from result.json.

Usage: view_runs_test.py HAPSYN PROBLEM_FILE WORK_DIR [--set path=value ...]. Exit 0 when every
check passes.
"""
import json
import os
import shutil
import subprocess
import sys

from view_browser_test import CHROMEDRIVER, browser
from view_process import ViewProcess
from view_result_test import check, failures, wait_state


def expected_counts(result):
    """(lines, points per line, run rows, cluster rows) from result.json alone."""
    runs = result["statistics"]["runs"]
    with_history = [r for r in runs if "history" in r]
    points = [sum(1 for g, b in zip(r["history"]["generation"], r["history"]["best"]) if b is not None)
              for r in with_history]
    clusters = result["statistics"].get("clusters", {}).get("clusters", [])
    return len(with_history), points, len(runs), len(clusters)


def check_page(driver, url, result):
    lines, points, run_rows, cluster_rows = expected_counts(result)
    driver.set_page_load_timeout(30)
    driver.get(url)
    state = wait_state(driver, "ready")
    check(state.get("ready") is True and not state.get("error"), f"page ready (error: {state.get('error')})")
    check(state.get("frontCount") == 0, "no front: frontCount 0")
    check(state.get("convergenceColumn") == "best", f"plots column {state.get('convergenceColumn')} = best")
    check(state.get("convergenceSeries") == lines, f"{state.get('convergenceSeries')} lines = {lines} runs with a history")
    check(state.get("convergencePoints") == points, f"points per line {state.get('convergencePoints')} = {points}")
    drawn = driver.execute_script("return document.querySelectorAll('#runs-plot polyline').length")
    check(drawn == lines, f"{drawn} polylines in the plot")
    check(state.get("runRows") == run_rows, f"runs table: {state.get('runRows')} rows = {run_rows} runs")
    rows = driver.execute_script("return document.querySelectorAll('#runs-table tbody tr').length")
    check(rows == run_rows, f"{rows} rows in the runs table")
    check(state.get("clusterRows") == cluster_rows, f"clusters table: {state.get('clusterRows')} rows = {cluster_rows} clusters")
    check(cluster_rows >= 1, f"the run has clusters ({cluster_rows})")


def main():
    hapsyn, problem, work = sys.argv[1:4]
    sets = [a for s in sys.argv[4:] for a in ("--set", s)]
    os.makedirs(work, exist_ok=True)
    for need in ("chromium", CHROMEDRIVER):
        if not shutil.which(need):
            print(f"FAIL {need} is not installed: bash scripts/setup.sh --browser")
            return 1
    run = os.path.join(work, "run")
    shutil.rmtree(run, ignore_errors=True)
    subprocess.run([hapsyn, "run", problem, "--out", run, "--quiet", *sets], check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(run, "result.json")) as f:
        result = json.load(f)
    with ViewProcess(hapsyn, run) as view:
        driver = browser()
        try:
            check_page(driver, view.url, result)
            shot = os.path.join(work, "view-runs.png")
            driver.save_screenshot(shot)
            check(os.path.getsize(shot) > 10000, f"screenshot {shot}")
        finally:
            driver.quit()
        code, _ = view.stop()
        check(code == 0, "the server stops with exit 0")
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
