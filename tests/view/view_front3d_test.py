#!/usr/bin/env python3
"""A front of three objectives in `hapsyn view`, in headless Chromium: it opens as a 3D scatter
(a non-blank canvas in the front panel) of result.json's front, a mouse click at the point
nearest the camera picks that point's design (state and drawn segments), and the check box turns
it to the 2D scatter with one circle per point. Saves a screenshot.

Usage: view_front3d_test.py HAPSYN PROBLEM_FILE WORK_DIR [--set path=value ...]. Exit 0 when
every check passes.
"""
import os
import sys
import time

from view_process import ViewProcess
from view_support import (check, check_not_blank, check_stops, chromium, click_at, finish, get_json, open_page,
                          page_state, prepare_study)


def main():
    prepared = prepare_study(sys.argv[1:])
    if prepared is None:
        return 1
    hapsyn, problem, work, run, result = prepared
    names = [o.get("name", o["metric"]) for o in result["problem"]["objectives"]]
    check(len(names) == 3 and len(result["front"]) >= 3, f"a front of {len(result['front'])} points, objectives {names}")
    with ViewProcess(hapsyn, run) as view:
        front = get_json(view.url + "api/result", timeout=30)["front"]
        with chromium() as driver:
            state = open_page(driver, view.url)
            check(state.get("front3d") is True and state.get("frontAxes") == names, f"3D scatter of {state.get('frontAxes')}")
            check(state.get("frontCount") == len(result["front"]), f"frontCount {state.get('frontCount')} = {len(result['front'])}")
            # The 3D scatter's canvas: white, the cube, the axes, shaded spheres; a blank one has 1.
            check_not_blank(driver, "the 3D scatter is drawn", "#front canvas", 20)
            where = [driver.execute_script("return window.hapsynView.frontPointPosition(arguments[0])", i)
                     for i in range(len(front["points"]))]
            nearest = min(range(len(where)), key=lambda i: where[i][2])  # in front of every other point
            click_at(driver, where[nearest][0], where[nearest][1])
            time.sleep(0.3)
            state = page_state(driver)
            point = front["points"][nearest]
            check(state.get("selectedPoint") == nearest and state.get("selectedDesign") == point["design"],
                  f"a click on the nearest point picks point {state.get('selectedPoint')} = {nearest}")
            check(state.get("drawnSegments") == point["segments"], "the 3D view draws its segments")
            driver.save_screenshot(os.path.join(work, "view-front3d.png"))
            driver.execute_script("window.hapsynView.showFront3d(false)")
            state = page_state(driver)
            circles = driver.execute_script("return document.querySelectorAll('#front-plot circle.point').length")
            check(state.get("front3d") is False and circles == len(result["front"]), f"2D again: {circles} circles")
        check_stops(view)
    return finish()


if __name__ == "__main__":
    sys.exit(main())
