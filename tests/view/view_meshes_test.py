#!/usr/bin/env python3
"""A URDF's meshes in `hapsyn view` (hapsyn/mesh_drawing.hpp), against the URDF read here:

  server   /api/study lists one mesh per drawable visual (an .stl or .dae <mesh> of a link the
           chain carries: the base -> tip path and the links fixed to it), each distinct file on
           a route /api/mesh/K whose bytes equal the file; the next route and /api/mesh/99 are
           404; the base's mesh sits at the base, the tip link's at the drawn sample.
  browser  the page (headless Chromium) loads every mesh (window.hapsynView.meshes equals that
           count, no error), places each where its pose and scale put the file's vertices (the
           box they take in the scene frame, from the STL's triangles or the COLLADA's
           positions read here), and renders a non-blank canvas; saves a screenshot.

Usage: view_meshes_test.py server|browser HAPSYN PROBLEM_FILE WORK_DIR. Exit 0 when every check passes.
"""
import json
import math
import os
import re
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

from view_process import ViewProcess
from view_support import (check, check_not_blank, check_stops, chromium, finish, open_page, run_study, screenshot,
                          wait_for)

HERE = os.path.dirname(os.path.abspath(__file__))


def resolve(name, urdf):
    """The file a <mesh filename> names: relative to the URDF, or package://NAME/... in an ancestor named NAME."""
    folder = os.path.dirname(os.path.abspath(urdf))
    if name.startswith("package://"):
        package, rest = name[len("package://"):].split("/", 1)
        while os.path.basename(folder) != package:
            folder = os.path.dirname(folder)
            assert folder != "/", name
        return os.path.join(folder, rest)
    return os.path.normpath(os.path.join(folder, name))


def drawable_visuals(urdf, base, tip):
    """[(link, file)] of the .stl/.dae visuals of the links the chain carries, in the file's order."""
    robot = ET.parse(urdf).getroot()
    joints = [(j.find("parent").get("link"), j.find("child").get("link"), j.get("type")) for j in robot.findall("joint")]
    parent = {child: p for p, child, _ in joints}
    carried = {tip}
    link = tip
    while link != base:
        link = parent[link]
        carried.add(link)
    grew = True
    while grew:  # links fixed to a carried link
        grew = False
        for p, child, kind in joints:
            if kind == "fixed" and p in carried and child not in carried:
                carried.add(child)
                grew = True
    out = []
    for link in robot.findall("link"):
        if link.get("name") not in carried:
            continue
        for visual in link.findall("visual"):
            mesh = visual.find("geometry/mesh")
            if mesh is not None and os.path.splitext(mesh.get("filename"))[1].lower() in (".stl", ".dae"):
                out.append((link.get("name"), resolve(mesh.get("filename"), urdf)))
    return out


def expected(problem):
    doc = json.load(open(problem))
    options = doc["mechanism"]["options"]
    urdf = os.path.join(os.path.dirname(os.path.abspath(problem)), "..", "share", options["urdf"])
    return drawable_visuals(urdf, options["base_link"], options["tip_link"])


def get(port, path):
    import http.client
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    c.request("GET", path)
    r = c.getresponse()
    data = r.read()
    c.close()
    return r.status, r.getheader("Content-Type", ""), data


def server(hapsyn, problem, work):
    visuals = expected(problem)
    check(len(visuals) > 0, f"the URDF has {len(visuals)} drawable visuals")
    with ViewProcess(hapsyn, problem) as view:
        _, _, body = get(view.port, "/api/study")
        study = json.loads(body)
        meshes = study.get("meshes", [])
        check(len(meshes) == len(visuals), f"/api/study lists {len(meshes)} meshes = the URDF's drawable visuals {len(visuals)}")
        check([m["link"] for m in meshes] == [link for link, _ in visuals], f"in the file's order: {[m['link'] for m in meshes]}")
        files = {}
        for m, (link, path) in zip(meshes, visuals):
            files.setdefault(m["route"], set()).add(path)
            status, kind, data = get(view.port, m["route"])
            want = open(path, "rb").read()
            check(status == 200 and data == want, f"{m['route']} ({link}): 200 and the {len(want)} bytes of {os.path.basename(path)}")
            check(m["name"] == os.path.basename(path) and m["format"] == os.path.splitext(path)[1][1:].lower(),
                  f"{link}: name {m['name']}, format {m['format']}")
            check(kind == ("model/vnd.collada+xml" if m["format"] == "dae" else "model/stl"), f"{m['route']}: Content-Type {kind}")
        routes = sorted(files, key=lambda r: int(r.rsplit("/", 1)[1]))
        check(routes == [f"/api/mesh/{k}" for k in range(len(routes))] and all(len(f) == 1 for f in files.values()),
              f"one route per distinct file, numbered from 0: {routes}")
        check(len(routes) == len({p for _, p in visuals}), f"{len(routes)} routes for {len({p for _, p in visuals})} distinct files")
        for path in (f"/api/mesh/{len(routes)}", "/api/mesh/99", "/api/mesh/", "/api/mesh/0/../1", "/api/mesh/-1"):
            status, _, _ = get(view.port, path)
            check(status == 404, f"GET {path} -> 404 ({status})")
        by_link = {m["link"]: m for m in meshes}
        base = by_link.get("base_link")
        check(base is not None and all(math.isclose(base["pose"][r][c], float(r == c), abs_tol=1e-12) for r in range(4) for c in range(4)),
              "the base's mesh at the scene frame's origin (identity pose)")
        tip = by_link.get(json.load(open(problem))["mechanism"]["options"]["tip_link"])
        drawn = study.get("drawn_position")
        check(tip is not None and drawn is not None and math.dist([tip["pose"][r][3] for r in range(3)], drawn) < 1e-9,
              f"the tip link's mesh at the drawn sample {drawn}")
        check_stops(view)
    warnings(hapsyn, problem, work)


def warnings(hapsyn, problem, work):
    """A copy of the study's URDF in `work` with a missing file, an .obj and a box: the study is
    still shown, one warning line each naming the link and the file, the rest drawn."""
    doc = json.load(open(problem))
    options = doc["mechanism"]["options"]
    share = os.path.join(os.path.dirname(os.path.abspath(problem)), "..", "share")
    text = open(os.path.join(share, options["urdf"])).read()
    meshes = os.path.abspath(os.path.join(share, "serial_chain", "meshes"))
    text = text.replace('filename="meshes/', f'filename="file://{meshes}/').replace('package://serial_chain/meshes/', f'{meshes}/')
    text = text.replace('<mesh filename="file://' + meshes + '/phantom_3r/gimbal.dae"/>', '<mesh filename="missing/gimbal.dae"/>')
    text = text.replace('<link name="turret">', '<link name="turret">\n    <visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual>'
                        '\n    <visual><geometry><mesh filename="turret.obj"/></geometry></visual>')
    os.makedirs(work, exist_ok=True)
    urdf = os.path.join(os.path.abspath(work), "bad_meshes.urdf")
    open(urdf, "w").write(text)
    doc["mechanism"]["options"]["urdf"] = urdf
    bad = os.path.join(work, "bad-meshes.json")
    json.dump(doc, open(bad, "w"))
    with ViewProcess(hapsyn, bad) as view:
        _, _, body = get(view.port, "/api/study")
        study = json.loads(body)
        view.stop()
    lines = [l.rstrip("\n") for l in view.stderr if "warning" in l]
    want = [f'hapsyn view: warning: {urdf}: link "turret" visual box: a primitive shape, not drawn (only .stl and .dae meshes are)',
            f'hapsyn view: warning: {urdf}: link "turret" visual mesh "turret.obj": not drawn (only .stl and .dae files are)',
            f'hapsyn view: warning: {urdf}: link "stylus_tip" visual mesh "missing/gimbal.dae": no such file (relative to the '
            f"URDF's folder: {os.path.join(os.path.abspath(work), 'missing/gimbal.dae')}); not drawn"]
    check(lines == want, "one warning per visual left out:\n  " + "\n  ".join(lines))
    check(len(study["meshes"]) == len(expected(problem)) - 1, f"the others drawn: {len(study['meshes'])}")


def file_vertices(path):
    """The vertices of a binary STL or of a COLLADA file's float arrays of positions [file units]."""
    import re
    import struct
    data = open(path, "rb").read()
    if path.lower().endswith(".stl"):
        count = struct.unpack_from("<I", data, 80)[0]
        return [struct.unpack_from("<3f", data, 84 + 50 * t + 12 + 12 * k) for t in range(count) for k in range(3)]
    numbers = [float(x) for a in re.findall(rb'<float_array id="[^"]*positions[^"]*"[^>]*>([^<]*)<', data) for x in a.split()]
    return [tuple(numbers[i:i + 3]) for i in range(0, len(numbers), 3)]


def placed_box(mesh, path):
    """The axis-aligned box of the file's vertex box corners, scaled and moved by the mesh's pose."""
    vertices = file_vertices(path)
    low = [min(v[k] for v in vertices) for k in range(3)]
    high = [max(v[k] for v in vertices) for k in range(3)]
    corners = [[(high if (c >> k) & 1 else low)[k] * mesh["scale"][k] for k in range(3)] for c in range(8)]
    pose = mesh["pose"]
    moved = [[sum(pose[r][k] * p[k] for k in range(3)) + pose[r][3] for r in range(3)] for p in corners]
    return [min(p[k] for p in moved) for k in range(3)], [max(p[k] for p in moved) for k in range(3)]


def meshes_loaded(state):
    """Whether the page is ready with every mesh tried, or failed."""
    return (state.get("ready") and state.get("meshesDone")) or state.get("error")


def browser(hapsyn, problem, work):
    count = len(expected(problem))
    os.makedirs(work, exist_ok=True)
    with ViewProcess(hapsyn, problem) as view:
        with chromium() as driver:
            state = open_page(driver, view.url, done=meshes_loaded)
            check(state.get("meshesDone") is True and state.get("meshErrors") == [], f"every mesh tried, no error: {state.get('meshErrors')}")
            check(state.get("meshes") == count, f"meshes loaded {state.get('meshes')} = the URDF's drawable visuals {count}")
            study = driver.execute_script("return fetch('/api/study').then(r => r.json())")
            boxes = state.get("meshBoxes", [])
            for mesh, (link, path), box in zip(study["meshes"], expected(problem), boxes):
                low, high = placed_box(mesh, path)
                near = all(abs(a - b) < 1e-6 for a, b in zip(low + high, box["min"] + box["max"]))
                check(box["link"] == link and near, f"{link} placed at [{', '.join(f'{x:.4f}' for x in box['min'])}] - "
                      f"[{', '.join(f'{x:.4f}' for x in box['max'])}] (file + pose + scale: "
                      f"[{', '.join(f'{x:.4f}' for x in low)}] - [{', '.join(f'{x:.4f}' for x in high)}])")
            time.sleep(0.5)  # a few frames with the meshes
            check_not_blank(driver)
            toggle = driver.execute_script("return !!document.querySelector('#capsules-toggle input')")
            check(toggle, "a check box shows or hides the capsules")
            screenshot(driver, os.path.join(work, "view-" + os.path.splitext(os.path.basename(problem))[0] + ".png"))
        check_stops(view)
    report(hapsyn, problem, work, count)


def report(hapsyn, problem, work, count):
    """hapsyn report of the study's result carries the mesh files: opened from disk, every mesh
    loads from the page itself."""
    run = os.path.join(work, "run")
    run_study(hapsyn, problem, run)
    r = subprocess.run([hapsyn, "report", run], capture_output=True, text=True, timeout=120)
    check(r.returncode == 0, f"report written: {r.stdout.strip()} {r.stderr.strip()}")
    page = os.path.join(run, "report.html")
    with open(page, encoding="utf-8") as f:
        html = f.read()
    embedded = re.findall(r'<script type="application/octet-stream" data-route="(/api/mesh/\d+)">', html)
    with ViewProcess(hapsyn, problem) as view:
        study = json.loads(get(view.port, "/api/study")[2])
    routes = sorted({m["route"] for m in study["meshes"]})
    check(sorted(embedded) == routes, f"the report embeds every mesh file: {embedded} = {routes}")
    check("/prototype.js" not in html, "the report leaves out the virtual prototype (it needs the server)")
    with chromium(offline=True) as driver:
        driver.get("file://" + os.path.abspath(page))
        state = wait_for(driver, meshes_loaded)
        check(state.get("meshesDone") is True and state.get("meshErrors") == [] and state.get("meshes") == count,
              f"the report loads its {state.get('meshes')} meshes from itself (= {count}; errors {state.get('meshErrors')})")


def main():
    mode, hapsyn, problem, work = sys.argv[1:5]
    {"server": server, "browser": browser}[mode](hapsyn, problem, work)
    return finish()


if __name__ == "__main__":
    sys.exit(main())
