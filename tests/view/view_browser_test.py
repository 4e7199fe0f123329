#!/usr/bin/env python3
"""The page of `hapsyn view` in a real browser (headless Chromium from Debian, driven by Selenium):
it renders a non-blank canvas, its point cloud has one point per sample and its colour range is
the chosen column's min/max, both computed here from the samples.csv that `hapsyn run` writes.
For a scene with a human (human_arm): the user drawn holds the drawn sample, seated at the
scene's shoulder position, upright (head above the shoulder, against gravity). Saves a screenshot.

Usage: view_browser_test.py HAPSYN PROBLEM_FILE WORK_DIR. Exit 0 when every check passes.
"""
import json
import math
import os
import sys
import time
import urllib.request

from view_process import ViewProcess, read_csv_columns
from view_support import (check, check_not_blank, check_stops, chromium, finish, open_page, page_state,
                          prepare_study, screenshot)


def check_human(state, study_doc, result, columns):
    """The figure against the run's own files: its shoulder is the resolved x_S_B, its palm lies
    |x_E_P| from the drawn sample's position in samples.csv, and its head is above the shoulder
    (gravity points along -z of the scene frame)."""
    options = result["problem"]["scene"]["options"]
    human = state.get("human") or {}
    check(human.get("drawn") is True, "the human is drawn")
    arm = human.get("arm") or [[math.nan] * 3] * 4
    shoulder = options["x_S_B"]
    check(math.dist(arm[0], shoulder) < 1e-12, f"the arm's shoulder {arm[0]} = scene.options.x_S_B {shoulder}")
    i = study_doc["drawn_sample"]
    sample = [float(columns[c][i]) for c in ("x", "y", "z")]
    offset = math.hypot(*options["x_E_P"])
    check(abs(math.dist(arm[-1], sample) - offset) < 1e-9,
          f"the palm {arm[-1]} is |x_E_P| = {offset} from the drawn sample {i} at {sample}")
    head = human.get("headCentre") or [math.nan] * 3
    check(head[2] > shoulder[2] + 0.1, f"the head {head} is above the shoulder (z up, gravity -z)")


def main():
    prepared = prepare_study(sys.argv[1:4])
    if prepared is None:
        return 1
    hapsyn, problem, work, out, result = prepared
    columns, rows = read_csv_columns(os.path.join(out, "samples.csv"))
    local_columns = list(columns)[list(columns).index("status") + 1:]
    chosen = local_columns[-1]  # not the page's default (the first): selecting it is tested too
    cells = [float(v) for v in columns[chosen] if v != ""]

    with ViewProcess(hapsyn, problem) as view:
        with chromium() as driver:
            state = open_page(driver, view.url)
            check(state.get("pointCount") == rows, f"pointCount {state.get('pointCount')} = samples.csv rows {rows}")
            check(state.get("columns") == local_columns, f"the page's columns = samples.csv's local columns {local_columns}")
            selected = driver.execute_script("return window.hapsynView.select(arguments[0])", chosen)
            time.sleep(0.5)  # a few frames with the new colours
            state = page_state(driver)
            low, high = state.get("colourRange") or (None, None)
            check(selected and state.get("objective") == chosen, f"objective {state.get('objective')} selected")
            check(low is not None and abs(low - min(cells)) <= 1e-9 * max(1.0, abs(low)) and
                  abs(high - max(cells)) <= 1e-9 * max(1.0, abs(high)),
                  f"colour range [{low}, {high}] = samples.csv {chosen} [{min(cells)}, {max(cells)}]")
            legend = driver.execute_script("return [document.getElementById('legend-min').textContent,"
                                           " document.getElementById('legend-max').textContent]")
            check(legend[0] != "–" and legend[1] != "–", f"legend shows the range: {legend}")
            if result["problem"]["scene"]["plugin"] == "human_arm":
                with urllib.request.urlopen(view.url + "api/study") as response:
                    check_human(state, json.load(response), result, columns)
            else:
                check(state.get("human") is None, "no human drawn for a scene without one")
            check_not_blank(driver)
            screenshot(driver, os.path.join(work, "view-" + os.path.splitext(os.path.basename(problem))[0] + ".png"))
        check_stops(view)
    return finish()


if __name__ == "__main__":
    sys.exit(main())
