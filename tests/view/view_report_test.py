#!/usr/bin/env python3
"""`hapsyn report RESULT_DIR`: one self-contained HTML file. Opened from disk (file://) in headless
Chromium with every network request blocked, it renders a non-blank canvas with one point per
sample (samples.csv) and one scatter point per front point (result.json), and clicking a point
shows its design; the file names no http(s) URL that it loads, and the browser fetched nothing
but data: URLs. Bad RESULT_DIRs and outputs are refused with a message naming them.

Usage: view_report_test.py HAPSYN PROBLEM_FILE WORK_DIR [--set path=value ...]. Exit 0 when every
check passes.
"""
import base64
import glob
import json
import os
import re
import shutil
import subprocess
import sys

from view_support import (check, check_not_blank, chromium, click_at, finish, open_page, prepare_study, screenshot,
                          wait_state)

# A URL the page would load: an element's src/href, an import or a fetch of an absolute URL.
LOADS = re.compile(r"""(?:\b(?:src|href)\s*=\s*["']?\s*(?:https?:)?//)|(?:\bfrom\s*["']https?:)|"""
                   r"""(?:\bimport\s*\(?\s*["']https?:)|(?:\bfetch\s*\(\s*["']https?:)|(?:url\(\s*["']?https?:)""")


def check_file(html):
    check(not LOADS.search(html), f"the page loads no http(s) URL ({LOADS.search(html)})")
    modules = re.findall(r'"data:text/javascript;base64,([A-Za-z0-9+/=]+)"', html)
    # Byte for byte the page's modules as the build embeds them (its manifest: route|type|file),
    # all but the page, app.js (inline) and the virtual prototype (it needs the server); the
    # base64 checked by an independent decoder.
    with open(os.environ["HAPSYN_WEB_MANIFEST"]) as f:
        assets = [line.rstrip("\n").split("|") for line in f if line.strip()]
    sources = [path for route, _, path in assets if route not in ("/", "/app.js", "/prototype.js")]
    check(len(modules) == len(sources) and len(sources) >= 5,
          f"{len(modules)} modules inlined as data: URLs ({len(sources)} in the manifest but the page, app.js and prototype.js)")
    want = sorted(open(p, "rb").read() for p in sources)
    check(sorted(base64.b64decode(m) for m in modules) == want,
          f"the data: modules decode to the files (sizes mod 3: {sorted(len(w) % 3 for w in want)})")
    found = [LOADS.search(base64.b64decode(m).decode("utf-8")) for m in modules]
    check(not any(found), f"no inlined module loads an http(s) URL ({[f.group(0) for f in found if f]})")
    check(html.count('type="application/json" data-route="/api/') == 3, "the three documents embedded")


def check_page(driver, report, result, rows):
    state = open_page(driver, "file://" + os.path.abspath(report), "report ready offline", timeout=60)
    check(state.get("pointCount") == rows, f"pointCount {state.get('pointCount')} = result.json samples_in_scene {rows}")
    check(state.get("frontCount") == len(result["front"]), f"frontCount {state.get('frontCount')} = {len(result['front'])}")
    check_not_blank(driver)
    last = len(result["front"]) - 1
    x, y = driver.execute_script("return window.hapsynView.frontPointPosition(arguments[0])", last)
    click_at(driver, x, y)
    state = wait_state(driver, "selectedDesign")
    fixed = result.get("design_fixed", {})
    check(state.get("selectedPoint") == last and state.get("selectedDesign") == {**fixed, **result["front"][last]["design"]},
          f"a click shows front point {last}'s design")
    loaded = driver.execute_script("return performance.getEntriesByType('resource').map(e => e.name)")
    check(all(not n.startswith(("http:", "https:")) for n in loaded), f"nothing fetched from a network: {loaded[:3]}")
    screenshot(driver, os.path.join(os.path.dirname(report), "report.png"))


HOSTILE = "</script><script>window.pwned = 1</script><!--"


def check_hostile(driver, hapsyn, run, work):
    """A result.json string holding markup stays a string: the report loads, runs none of it."""
    folder = os.path.join(work, "hostile")
    shutil.rmtree(folder, ignore_errors=True)
    shutil.copytree(run, folder, ignore=shutil.ignore_patterns("report*"))
    path = os.path.join(folder, "result.json")
    with open(path) as f:
        result = json.load(f)
    result["statistics"]["algorithm"] = HOSTILE
    with open(path, "w") as f:
        json.dump(result, f)
    r = subprocess.run([hapsyn, "report", folder], capture_output=True, text=True, timeout=120)
    html = open(os.path.join(folder, "report.html"), encoding="utf-8").read() if r.returncode == 0 else ""
    check(HOSTILE not in html and html.count("</script>") == html.count("<script"), "markup in a string is escaped")
    driver.get("file://" + os.path.abspath(os.path.join(folder, "report.html")))
    state = wait_state(driver, "ready", timeout=60)
    pwned = driver.execute_script("return window.pwned === undefined")
    check(state.get("ready") is True and pwned, f"the report loads and runs none of it (error: {state.get('error')})")


def check_errors(hapsyn, run, work):
    empty = os.path.join(work, "empty")
    os.makedirs(empty, exist_ok=True)
    missing = os.path.join(work, "no-such-dir")
    cases = (([missing], f"report: {missing}: not a directory: give a result directory (one holding result.json)"),
             ([os.path.join(run, "result.json")], "result.json: not a directory"),
             ([empty], f"report: {empty}: no result.json (nor sweep.json, compare.json) in it: give the output directory of hapsyn run, sweep or compare"),
             ([run, "-o", os.path.join(missing, "r.html")], f"report: cannot write {missing}/r.html.tmp-"),
             ([run, "-o", empty], f"report: cannot rename {empty}.tmp-"))
    for args, message in cases:
        r = subprocess.run([hapsyn, "report", *args], capture_output=True, text=True, timeout=120)
        check(r.returncode == 1 and message in r.stderr, f"report {' '.join(args)}: exit 1, '{message}' ({r.stderr.strip()})")
    check(not os.path.exists(missing), "nothing created for a refused output")
    check(not glob.glob(empty + ".tmp-*") and os.path.isdir(empty), "a refused rename leaves no temporary file")


def main():
    prepared = prepare_study(sys.argv[1:])
    if prepared is None:
        return 1
    hapsyn, problem, work, run, result = prepared
    rows = result["samples_in_scene"]
    r = subprocess.run([hapsyn, "report", run], capture_output=True, text=True, timeout=120)
    report = os.path.join(run, "report.html")
    check(r.returncode == 0 and r.stdout.startswith(f"hapsyn report: {report} ("), f"report written: {r.stdout.strip()}")
    check(not glob.glob(report + ".tmp-*"), "no temporary file left")
    other = os.path.join(work, "elsewhere.html")
    r = subprocess.run([hapsyn, "report", run, "-o", other], capture_output=True, text=True, timeout=120)
    check(r.returncode == 0 and os.path.isfile(other), "-o writes another file")
    with open(report, encoding="utf-8") as f:
        html = f.read()
    check(html == open(other, encoding="utf-8").read(), "both reports are the same file")
    check_file(html)
    with chromium(offline=True) as driver:
        check_page(driver, report, result, rows)
        check_hostile(driver, hapsyn, run, work)
    check_errors(hapsyn, run, work)
    return finish()


if __name__ == "__main__":
    sys.exit(main())
