#!/usr/bin/env python3
"""A front of three objectives in `hapsyn view`, in headless Chromium: it opens as a 3D scatter
(a non-blank canvas in the front panel) of result.json's front, a mouse click at the point
nearest the camera picks that point's design (state and drawn segments), and the check box turns
it to the 2D scatter with one circle per point. Saves a screenshot.

Usage: view_front3d_test.py HAPSYN PROBLEM_FILE WORK_DIR [--set path=value ...]. Exit 0 when
every check passes.
"""
import json
import os
import shutil
import subprocess
import sys
import time
import urllib.request

from view_browser_test import CHROMEDRIVER, browser
from view_process import ViewProcess
from view_result_test import check, click_at, failures, wait_state

# Distinct colours of the 3D scatter's canvas (white, the cube, the axes, shaded spheres); a
# blank one has 1.
COUNT_FRONT_COLOURS = """
const source = document.querySelector('#front canvas');
const copy = document.createElement('canvas');
copy.width = source.width; copy.height = source.height;
const context = copy.getContext('2d');
context.drawImage(source, 0, 0);
const data = context.getImageData(0, 0, copy.width, copy.height).data;
const seen = new Set();
for (let i = 0; i < data.length; i += 4) seen.add((data[i] << 16) | (data[i + 1] << 8) | data[i + 2]);
return seen.size;
"""


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
    names = [o.get("name", o["metric"]) for o in result["problem"]["objectives"]]
    check(len(names) == 3 and len(result["front"]) >= 3, f"a front of {len(result['front'])} points, objectives {names}")
    with ViewProcess(hapsyn, run) as view:
        front = json.load(urllib.request.urlopen(view.url + "api/result", timeout=30))["front"]
        driver = browser()
        try:
            driver.set_page_load_timeout(30)
            driver.get(view.url)
            state = wait_state(driver, "ready")
            check(state.get("ready") is True and not state.get("error"), f"page ready (error: {state.get('error')})")
            check(state.get("front3d") is True and state.get("frontAxes") == names, f"3D scatter of {state.get('frontAxes')}")
            check(state.get("frontCount") == len(result["front"]), f"frontCount {state.get('frontCount')} = {len(result['front'])}")
            colours = driver.execute_script(COUNT_FRONT_COLOURS)
            check(colours > 20, f"the 3D scatter is drawn: {colours} distinct colours (> 20)")
            where = [driver.execute_script("return window.hapsynView.frontPointPosition(arguments[0])", i)
                     for i in range(len(front["points"]))]
            nearest = min(range(len(where)), key=lambda i: where[i][2])  # in front of every other point
            click_at(driver, where[nearest][0], where[nearest][1])
            time.sleep(0.3)
            state = driver.execute_script("return JSON.parse(JSON.stringify(window.hapsynView))")
            point = front["points"][nearest]
            check(state.get("selectedPoint") == nearest and state.get("selectedDesign") == point["design"],
                  f"a click on the nearest point picks point {state.get('selectedPoint')} = {nearest}")
            check(state.get("drawnSegments") == point["segments"], "the 3D view draws its segments")
            driver.save_screenshot(os.path.join(work, "view-front3d.png"))
            driver.execute_script("window.hapsynView.showFront3d(false)")
            state = driver.execute_script("return JSON.parse(JSON.stringify(window.hapsynView))")
            circles = driver.execute_script("return document.querySelectorAll('#front-plot circle.point').length")
            check(state.get("front3d") is False and circles == len(result["front"]), f"2D again: {circles} circles")
        finally:
            driver.quit()
        code, _ = view.stop()
        check(code == 0, "the server stops with exit 0")
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
