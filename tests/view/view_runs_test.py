#!/usr/bin/env python3
"""A GA result directory in `hapsyn view`, in headless Chromium: the convergence plot has one line
per run with one point per generation of that run's history where it has a best score, and the
runs' and clusters' tables one row per run and per cluster, all counted here from result.json.

Usage: view_runs_test.py HAPSYN PROBLEM_FILE WORK_DIR [--set path=value ...]. Exit 0 when every
check passes.
"""
import os
import sys

from view_process import ViewProcess
from view_support import check, check_stops, chromium, finish, open_page, prepare_study, screenshot


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
    state = open_page(driver, url)
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
    prepared = prepare_study(sys.argv[1:])
    if prepared is None:
        return 1
    hapsyn, problem, work, run, result = prepared
    with ViewProcess(hapsyn, run) as view:
        with chromium() as driver:
            check_page(driver, view.url, result)
            screenshot(driver, os.path.join(work, "view-runs.png"))
        check_stops(view)
    return finish()


if __name__ == "__main__":
    sys.exit(main())
