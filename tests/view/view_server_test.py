#!/usr/bin/env python3
"""The server of `hapsyn view`: what it serves, what it refuses, that a bad client harms no other,
that it listens on loopback by default and stops cleanly; the API's documents against independent
computations (samples.csv of `hapsyn run`, the five-bar's geometry).

Usage: view_server_test.py HAPSYN PROBLEM_FILE WORK_DIR. Exit 0 when every check passes.
"""
import http.client
import json
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import time

from view_process import ViewProcess, read_csv_columns

failures = []
HOST = b""  # b"Host: 127.0.0.1:PORT\r\n", set in main()


def check(condition, what):
    print(("ok   " if condition else "FAIL ") + what, flush=True)
    if not condition:
        failures.append(what)


def raw(port, data, read=True, timeout=5):
    """Sends raw bytes; returns the status code of the answer (None when there is none) and it."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(data)
        if not read:
            return None, b""
        answer = b""
        try:
            while True:
                chunk = s.recv(65536)
                if not chunk:
                    break
                answer += chunk
                if b"\r\n\r\n" in answer and b"Connection: close" not in answer and len(answer) > 64:
                    head = answer.split(b"\r\n\r\n", 1)[0]
                    length = [int(l.split(b":")[1]) for l in head.split(b"\r\n") if l.lower().startswith(b"content-length")]
                    if length and len(answer) >= len(head) + 4 + length[0]:
                        break
        except socket.timeout:
            pass
    status = int(answer.split(b" ", 2)[1]) if answer.startswith(b"HTTP/") else None
    return status, answer


def get(port, path, method="GET", headers=None, body=None):
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    c.request(method, path, body=body, headers=headers or {})
    r = c.getresponse()
    data = r.read()
    c.close()
    return r.status, dict(r.getheaders()), data


def listening_addresses(port):
    """Local addresses (hex, as /proc/net/tcp{,6} show them) of sockets listening on `port`."""
    found = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        if not os.path.exists(table):
            continue
        for line in open(table).read().splitlines()[1:]:
            cells = line.split()
            address, hex_port = cells[1].split(":")
            if int(hex_port, 16) == port and cells[3] == "0A":  # 0A = LISTEN
                found.append(address)
    return found


def check_routes(port, rows):
    for path, kind in (("/", "text/html"), ("/app.js", "text/javascript"), ("/figure.js", "text/javascript"),
                       ("/three.module.js", "text/javascript"),
                       ("/OrbitControls.js", "text/javascript"), ("/api/study", "application/json"),
                       ("/api/samples", "application/json"), ("/front.js", "text/javascript"), ("/front3d.js", "text/javascript"), ("/plots.js", "text/javascript"),
                       ("/api/result", "application/json")):
        status, headers, body = get(port, path)
        check(status == 200 and headers.get("Content-Type", "").startswith(kind) and len(body) > 0,
              f"GET {path}: 200 {kind} ({status}, {headers.get('Content-Type')}, {len(body)} bytes)")
    status, _, body = get(port, "/api/samples?column=1")
    check(status == 200 and json.loads(body)["count"] == rows, "a query string is ignored: /api/samples?column=1")


def check_refusals(port):
    for method in ("POST", "PUT", "DELETE", "HEAD", "OPTIONS"):
        status, headers, _ = get(port, "/", method=method)
        check(status == 405 and headers.get("Allow") == "GET", f"{method} / -> 405 with Allow: GET ({status})")
    for path in ("/nope", "/index.html", "/web/app.js", "/api", "/api/study/", "//etc/passwd"):
        status, _, body = get(port, path)
        check(status == 404 and b"root:" not in body, f"GET {path} -> 404 ({status})")
    for target in (b"/../../etc/passwd", b"/%2e%2e/%2e%2e/etc/passwd", b"/..%2f..%2fetc%2fpasswd", b"/app.js/../../../etc/passwd"):
        status, answer = raw(port, b"GET " + target + b" HTTP/1.1\r\n" + HOST + b"Connection: close\r\n\r\n")
        check(status == 404 and b"root:" not in answer, f"path traversal {target.decode()} -> 404 ({status})")
    status, _ = raw(port, b"GET / HTTP/1.1\r\n" + HOST + b"X-Big: " + b"a" * 20000 + b"\r\nConnection: close\r\n\r\n")
    check(status == 431, f"a 20 kB header -> 431 ({status})")
    status, _ = raw(port, b"GET / HTTP/1.1\r\n" + HOST + b"Content-Length: 100000\r\nConnection: close\r\n\r\n" + b"a" * 4096)
    check(status == 413, f"a 100 kB body -> 413 ({status})")
    status, _ = raw(port, b"GARBAGE\r\n\r\n")
    check(status == 400, f"a malformed request line -> 400 ({status})")
    status, _ = raw(port, b"GET / HTTP/1.1\r\nHost 127.0.0.1\r\n\r\n")
    check(status == 400, f"a malformed header -> 400 ({status})")


def check_hosts(port):
    for host, want in ((f"localhost:{port}", 200), (f"127.0.0.1:{port}", 200), ("evil.example", 403),
                       (f"evil.example:{port}", 403), ("127.0.0.1", 403), ("", 403)):
        status, _, _ = get(port, "/api/study", headers={"Host": host})
        check(status == want, f"Host '{host}' -> {want} ({status})")


def check_bad_clients(port):
    # Half a request, then gone; a client that connects and says nothing, held open meanwhile.
    raw(port, b"GET /api/sam", read=False)
    raw(port, b"GET / HTTP/1.1\r\n" + HOST + b"Content-Length: 50\r\n\r\nabc", read=False)
    silent = socket.create_connection(("127.0.0.1", port))
    slow = socket.create_connection(("127.0.0.1", port))
    slow.sendall(b"GET / HTTP/1.1\r\n")
    t0 = time.time()
    status, _, body = get(port, "/api/study")
    took = time.time() - t0
    check(status == 200 and json.loads(body)["name"] and took < 2.0,
          f"a good request while two clients stall and two left mid-request: 200 in {took:.3f} s")
    silent.close()
    slow.close()
    # Keep-alive: two requests on one connection.
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    c.request("GET", "/app.js")
    first = c.getresponse().read()
    c.request("GET", "/api/study")
    second = c.getresponse()
    check(len(first) > 0 and second.status == 200, "two requests on one kept-alive connection")
    c.close()


def check_fivebar_drawing(study):
    """The five-bar's links from its design alone: A1 = (-l0/2, -r), A2 = (l0/2, -r), |A B| = l1,
    |B E| = l2, E the drawn sample's position."""
    d = study["design"]
    links = [s for s in study["segments"] if s["name"] == "links"]
    check(len(links) == 1 and len(links[0]["points"]) == 5, "fivebar: one 'links' polyline of 5 points")
    if len(links) != 1 or len(links[0]["points"]) != 5:
        return
    a1, b1, e, b2, a2 = links[0]["points"]
    near = lambda p, q: math.dist(p, q) < 1e-9
    check(near(a1, (-d["l0"] / 2, -d["r"], 0)) and near(a2, (d["l0"] / 2, -d["r"], 0)), "fivebar: actuated joints at (-+l0/2, -r)")
    check(abs(math.dist(a1, b1) - d["l1"]) < 1e-9 and abs(math.dist(a2, b2) - d["l1"]) < 1e-9, "fivebar: |A B| = l1")
    check(abs(math.dist(b1, e) - d["l2"]) < 1e-9 and abs(math.dist(b2, e) - d["l2"]) < 1e-9, "fivebar: |B E| = l2")
    check(near(e, study["drawn_position"]), "fivebar: the links end at the drawn sample")


def check_result_dir(hapsyn, problem, work):
    out = os.path.join(work, "run")
    shutil.rmtree(out, ignore_errors=True)
    subprocess.run([hapsyn, "run", problem, "--out", out, "--quiet"], check=True, stdout=subprocess.DEVNULL)
    columns, rows = read_csv_columns(os.path.join(out, "samples.csv"))
    result = json.load(open(os.path.join(out, "result.json")))
    with ViewProcess(hapsyn, out) as view:
        _, _, body = get(view.port, "/api/samples")
        samples = json.loads(body)
        _, _, body = get(view.port, "/api/study")
        study = json.loads(body)
        _, _, body = get(view.port, "/api/result")
        front = json.loads(body)["front"]
        view.stop()
    check(front is None and "front" not in result, "result dir without a front: /api/result's front is null")
    check(samples["values_from"] == "samples.csv" and samples["count"] == rows, f"result dir: {rows} samples from samples.csv")
    check(study["design"] == result["best"]["design"], "result dir: the design is result.json's best.design")
    for column in samples["columns"]:
        cells = [float(v) for v in columns[column["name"]] if v != ""]
        check(cells and math.isclose(column["min"], min(cells), rel_tol=1e-9) and math.isclose(column["max"], max(cells), rel_tol=1e-9),
              f"result dir: {column['name']} range [{column['min']}, {column['max']}] = samples.csv's")
    check(all(x == y for x, y in zip(samples["status"], columns["status"])), "result dir: per-sample status = samples.csv's")
    return columns, rows


def check_result_dir_errors(hapsyn, work):
    """A result directory view cannot show: each refused with exit 1 and a message naming why."""
    good = os.path.join(work, "run")
    result = json.load(open(os.path.join(good, "result.json")))
    csv_lines = open(os.path.join(good, "samples.csv")).read().splitlines(keepends=True)

    def variant(name, result_doc=None, csv=None):
        folder = os.path.join(work, "bad-" + name)
        shutil.rmtree(folder, ignore_errors=True)
        os.makedirs(folder)
        if result_doc is not None:
            json.dump(result_doc, open(os.path.join(folder, "result.json"), "w"))
        if csv is not None:
            open(os.path.join(folder, "samples.csv"), "w").write("".join(csv))
        return folder

    without_best = {k: v for k, v in result.items() if k != "best"}
    without_problem = {k: v for k, v in result.items() if k != "problem"}
    without_l1 = json.loads(json.dumps(result))
    del without_l1["best"]["design"]["l1"]
    renamed = [csv_lines[0].replace("gdi.sigma_max_M", "gdi.other")] + csv_lines[1:]
    short_row = csv_lines[:5] + [csv_lines[5].rsplit(",", 1)[0] + "\n"] + csv_lines[6:]
    rows = len(csv_lines) - 1
    cases = (
        (variant("empty"), "is a directory without result.json: give a problem file or a result directory"),
        (variant("no-best", without_best), 'no "best.design" and no front (status'),
        (variant("no-problem", without_problem), 'no "problem" object: not a result.json that hapsyn run wrote'),
        (variant("no-l1", without_l1), "result.json: best.design.l1: no number for design component l1"),
        (variant("rows", result, csv_lines[:-1]), f"{rows - 1} rows, the scene has {rows} samples"),
        (variant("column", result, renamed), 'no column "gdi.sigma_max_M"'),
        (variant("cells", result, short_row), "row 5 has"),
    )
    for folder, message in cases:
        r = subprocess.run([hapsyn, "view", folder, "--port", "0"], capture_output=True, text=True, timeout=60)
        check(r.returncode == 1 and message in r.stderr, f"{os.path.basename(folder)}: exit 1, '{message}' ({r.stderr.strip()})")


def check_free_design(hapsyn, problem):
    """A problem file whose design is free (a grid study) is shown at the midpoint of its bounds."""
    grid_study = os.path.join(os.path.dirname(problem), "fivebar-gii-coarse.json")
    design = json.load(open(grid_study))["design"]
    with ViewProcess(hapsyn, grid_study) as view:
        _, _, body = get(view.port, "/api/study")
        shown = json.loads(body)["design"]
        view.stop()
    want = {k: (v["lower"] + v["upper"]) / 2 for k, v in design.items()}
    check(shown.keys() == want.keys() and all(math.isclose(shown[k], want[k], rel_tol=1e-12) for k in want),
          f"a free design at the midpoint of its bounds: {shown}")


def check_errors(hapsyn, problem):
    r = subprocess.run([hapsyn, "view", problem, "--host", "not-an-address", "--port", "0"], capture_output=True, text=True, timeout=120)
    check(r.returncode == 1 and "--host not-an-address: not an IP address" in r.stderr, f"--host not-an-address: exit 1 ({r.stderr.strip()})")
    r = subprocess.run([hapsyn, "view", "/nonexistent/problem.json"], capture_output=True, text=True, timeout=60)
    check(r.returncode == 1 and "/nonexistent/problem.json" in r.stderr, f"a missing file: exit 1 ({r.stderr.strip()})")
    r = subprocess.run([hapsyn, "view", problem, "--port", "70000"], capture_output=True, text=True, timeout=60)
    check(r.returncode == 2, "--port 70000: usage error (exit 2)")
    with ViewProcess(hapsyn, problem) as first:
        r = subprocess.run([hapsyn, "view", problem, "--port", str(first.port)], capture_output=True, text=True, timeout=120)
        check(r.returncode == 1 and f"cannot listen on 127.0.0.1 port {first.port}" in r.stderr,
              f"a port in use: exit 1 ({r.stderr.strip()})")
        first.stop()


def main():
    hapsyn, problem, work = sys.argv[1:4]
    os.makedirs(work, exist_ok=True)
    csv_columns, rows = check_result_dir(hapsyn, problem, work)
    with ViewProcess(hapsyn, problem) as view:
        check(view.url.startswith("http://127.0.0.1:"), f"prints the URL on loopback: {view.url}")
        addresses = listening_addresses(view.port)
        check(addresses == ["0100007F"], f"listens on 127.0.0.1 only by default: {addresses}")
        global HOST
        HOST = f"Host: 127.0.0.1:{view.port}\r\n".encode()
        check_routes(view.port, rows)
        check_hosts(view.port)
        check_refusals(view.port)
        check_bad_clients(view.port)
        _, _, body = get(view.port, "/api/study")
        study = json.loads(body)
        _, _, body = get(view.port, "/api/samples")
        samples = json.loads(body)
        check(samples["values_from"] == "evaluated" and samples["count"] == rows, "problem file: evaluated on every sample")
        same = all(c["name"] in csv_columns and
                   all((v is None and cell == "") or (v is not None and cell != "" and math.isclose(v, float(cell), rel_tol=1e-8, abs_tol=1e-12))
                       for v, cell in zip(c["values"], csv_columns[c["name"]]))
                   for c in samples["columns"])
        check(same and samples["columns"], "problem file: every local value equals hapsyn run's samples.csv (10 digits)")
        if study["mechanism"] == "fivebar":
            check_fivebar_drawing(study)
        status, _, _ = get(view.port, "/")
        check(status == 200, "still serving after every bad request")
        code, rest = view.stop(signal.SIGINT)
        check(code == 0 and "hapsyn view: stopped" in rest, f"SIGINT: exit 0, 'stopped' ({code})")
    with ViewProcess(hapsyn, problem) as view:
        code, _ = view.stop(signal.SIGTERM)
        check(code == 0, f"SIGTERM: exit 0 ({code})")
    check_errors(hapsyn, problem)
    check_result_dir_errors(hapsyn, work)
    check_free_design(hapsyn, problem)
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
