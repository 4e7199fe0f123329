#!/usr/bin/env python3
"""The Pareto front of a result directory in `hapsyn view`, in a real browser (headless Chromium,
Selenium): /api/result holds result.json's front (objectives, each design with design_fixed, the
five-bar drawn from that design alone), the page's scatter has one point per front point, and a
mouse click at a point's position shows that design: its values in the panel state and its links
in the 3D view. A result whose front lacks a design component is refused with a message naming
it. Saves a screenshot.

Usage: view_result_test.py HAPSYN PROBLEM_FILE WORK_DIR [--set path=value ...]. Exit 0 when every
check passes.
"""
import json
import math
import os
import shutil
import subprocess
import sys
import time

from view_process import ViewProcess
from view_support import (check, check_not_blank, check_stops, chromium, click_at, finish, get_json, open_page,
                          page_state, prepare_study, screenshot)


def fivebar_links_match(design, segments):
    """Whether the five-bar's 'links' polyline A1 B1 E B2 A2 fits the design alone:
    A1 = (-l0/2, -r), A2 = (l0/2, -r), |A B| = l1, |B E| = l2."""
    links = [s["points"] for s in segments if s["name"] == "links"]
    if len(links) != 1 or len(links[0]) != 5:
        return False
    a1, b1, e, b2, a2 = links[0]
    near = lambda a, b: abs(a - b) < 1e-9
    return (math.dist(a1, (-design["l0"] / 2, -design["r"], 0)) < 1e-9 and
            math.dist(a2, (design["l0"] / 2, -design["r"], 0)) < 1e-9 and
            near(math.dist(a1, b1), design["l1"]) and near(math.dist(a2, b2), design["l1"]) and
            near(math.dist(b1, e), design["l2"]) and near(math.dist(b2, e), design["l2"]))


def check_api(front, result, samples, study):
    """/api/result's front against result.json; without best.design the page starts at the
    front point of the highest score."""
    expected, fixed = result["front"], result.get("design_fixed", {})
    top = max(range(len(expected)), key=lambda i: expected[i]["score"])
    check(study["design"] == {**fixed, **expected[top]["design"]}, f"/api/study: the design of front point {top} (highest score)")
    points = front["points"] if front else []
    check(len(points) == len(expected), f"/api/result: {len(points)} front points = result.json's {len(expected)}")
    names = [o["name"] for o in front["objectives"]] if front else []
    want = [o.get("name", o["metric"]) for o in result["problem"]["objectives"]]
    check(names == want, f"/api/result: objectives {names} = the problem's {want}")
    check(all(o["sense"] == "maximize" for o in front["objectives"]), "/api/result: both objectives maximised")
    same = all(p["objectives"] == e["objectives"] and p["design"] == {**fixed, **e["design"]}
               for p, e in zip(points, expected))
    check(same, "/api/result: every point's objectives and design (with design_fixed) = result.json's")
    drawn = [p for p in points if p["drawn_sample"] is not None]
    check(len(drawn) == len(points), f"every front design drawn ({len(drawn)} of {len(points)})")
    check(all(fivebar_links_match(p["design"], p["segments"]) for p in drawn), "every drawing fits its design (five-bar)")
    check(all(math.dist(next(s for s in p["segments"] if s["name"] == "links")["points"][2],
                        samples["positions"][3 * p["drawn_sample"]:3 * p["drawn_sample"] + 3]) < 1e-9 for p in drawn),
          "every drawing ends at its drawn sample's position")


def check_page(driver, url, result, front, best, work):
    state = open_page(driver, url)
    check(state.get("frontCount") == len(result["front"]), f"frontCount {state.get('frontCount')} = {len(result['front'])}")
    # NSGA-II's one history: its first objective's ideal per generation by default.
    history = result["statistics"]["history"]
    column = state.get("convergenceColumn")
    first = front["objectives"][0]["name"]
    want = [sum(1 for v in history["ideal"][first] if v is not None)]
    check(column == "ideal." + first and state.get("convergenceSeries") == 1 and
          state.get("convergencePoints") == want, f"convergence: {column}, {state.get('convergencePoints')} points = {want}")
    circles = driver.execute_script("return document.querySelectorAll('#front-plot circle.point').length")
    check(circles == len(result["front"]), f"{circles} circles in the scatter")
    check(state.get("frontAxes") == [o["name"] for o in front["objectives"][:2]], f"axes {state.get('frontAxes')}")
    # The point whose design is farthest from the shown design's (it must be drawn differently)
    # among those on top at their centre (a click there hits that point).
    distance = lambda p: sum((p["design"][k] - best[k]) ** 2 for k in best if isinstance(best[k], (int, float)))
    on_top = driver.execute_script("""return [...document.querySelectorAll('#front-plot circle.point')].map((c, i) => {
        const [x, y] = window.hapsynView.frontPointPosition(i); return document.elementFromPoint(x, y) === c; })""")
    hit = [i for i, top in enumerate(on_top) if top]
    check(len(hit) > 1, f"{len(hit)} front points on top at their centre")
    target = max(hit or [0], key=lambda i: distance(front["points"][i]))
    point = front["points"][target]
    x, y = driver.execute_script("return window.hapsynView.frontPointPosition(arguments[0])", target)
    click_at(driver, x, y)
    time.sleep(0.5)
    state = page_state(driver)
    check(state.get("selectedPoint") == target, f"click at ({x:.0f}, {y:.0f}) selects point {state.get('selectedPoint')} = {target}")
    check(state.get("selectedDesign") == point["design"], f"selectedDesign = the point's {point['design']}")
    check(state.get("drawnSegments") == point["segments"], "the 3D view draws the point's segments")
    check(distance(point) == 0 or state.get("drawnSegments") != driver.execute_script(
        "return fetch('/api/study').then(r => r.json()).then(s => s.segments)"), "which differ from the best design's")
    check(fivebar_links_match(state.get("selectedDesign"), state.get("drawnSegments") or []), "drawn links fit the selected design")
    info = driver.execute_script("return document.getElementById('front-info').textContent")
    check(info.startswith(f"point {target + 1}:") and all(k in info for k in point["design"]), f"panel: {info[:80]}…")
    check_not_blank(driver)
    screenshot(driver, os.path.join(work, "view-front.png"))


def check_bad_front(hapsyn, run, work):
    """A front point without a design component: `hapsyn view` exits 1 naming it."""
    bad = os.path.join(work, "bad-front")
    shutil.rmtree(bad, ignore_errors=True)
    shutil.copytree(run, bad)
    path = os.path.join(bad, "result.json")
    with open(path) as f:
        result = json.load(f)
    variable = next(iter(result["front"][0]["design"]))
    del result["front"][0]["design"][variable]
    with open(path, "w") as f:
        json.dump(result, f)
    p = subprocess.run([hapsyn, "view", bad, "--port", "0"], capture_output=True, text=True, timeout=120)
    want = f"result.json: front[0].design.{variable}: no number for design component {variable}"
    check(p.returncode != 0 and want in p.stderr, f"bad front refused: {p.stderr.strip()[-160:]}")


def main():
    prepared = prepare_study(sys.argv[1:])
    if prepared is None:
        return 1
    hapsyn, problem, work, run, result = prepared
    check(len(result.get("front", [])) >= 2, f"the run has a front of {len(result.get('front', []))} points")
    with ViewProcess(hapsyn, run) as view:
        get = lambda route: get_json(view.url.rstrip("/") + route, timeout=30)
        front, study, samples = get("/api/result")["front"], get("/api/study"), get("/api/samples")
        check_api(front, result, samples, study)
        with chromium() as driver:
            check_page(driver, view.url, result, front, study["design"], work)
        check_stops(view)
    check_bad_front(hapsyn, run, work)
    return finish()


if __name__ == "__main__":
    sys.exit(main())
