#!/usr/bin/env python3
"""The virtual prototype's live mode (`hapsyn view`, WebSocket /live and /live/watch), driven by
the example bridge's stdlib WebSocket client (examples/live_bridge/stream_recording.py):
- the poses of a recording as the scene processed it (its "shoulder_pose" and "time" attributes,
  from the Python module) give frames whose joint angles equal the IK's (the Python module's
  quantities) and the replay's for the same samples; rates appear once the filter has its poses;
- every bad message gets an error frame naming the field, the value and the rule, and the
  connection keeps working (a good message after each); a message beyond the hard limit closes
  that connection only; foreign Host or Origin headers and other targets are refused;
- a watcher on /live/watch gets every frame; the page in headless Chromium, in live mode, moves
  the arm to the frames a bridge's poses give; its WebXR path (without a headset) turns a
  controller pose into the same frame and places the target at the controller. Saves a screenshot.

Usage: view_live_test.py HAPSYN PROBLEM_FILE WORK_DIR [--socket-only]
(PYTHONPATH holds the build's python/). --socket-only: the WebSocket's rules alone, with the raw
rows of a shipped recording as poses, without the Python module and the browser (so that the
sanitizer build runs it).
"""
import json
import os
import socket
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "examples", "live_bridge"))

from stream_recording import WebSocket  # noqa: E402
from view_process import ViewProcess  # noqa: E402
from view_support import browser_missing, chromium, check, check_stops, finish, get_json, screenshot, wait_for  # noqa: E402


def upgrade_status(port, target, host=None, origin=None):
    """The status line a WebSocket upgrade request gets."""
    s = socket.create_connection(("127.0.0.1", port), timeout=10)
    headers = [f"GET {target} HTTP/1.1", f"Host: {host or f'127.0.0.1:{port}'}", "Upgrade: websocket",
               "Connection: Upgrade", "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==", "Sec-WebSocket-Version: 13"]
    if origin:
        headers.append(f"Origin: {origin}")
    s.sendall(("\r\n".join(headers) + "\r\n\r\n").encode())
    line = s.recv(4096).split(b"\r\n", 1)[0].decode()
    s.close()
    return line


def message(t, pose):
    return json.dumps({"t": float(t), "position": [float(v) for v in pose[:3]], "orientation": [float(v) for v in pose[3:7]]})


def recording_poses():
    """The raw rows of a shipped recording: time stamps and (x, y, z, qw, qx, qy, qz) rows."""
    from stream_recording import read_recording
    path = os.path.join(HERE, "..", "..", "share", "motion", "synthetic", "csv", "S01", "drinking.csv")
    rows = read_recording(path)
    return [r[0] for r in rows], [r[1] + r[2] for r in rows]


def check_other_studies(hapsyn, problem, work):
    """A study without a motion scene: /live answers with why; a motion study whose metric asks
    for the reachable share only: the replay has no bars and says why."""
    other = os.path.join(HERE, "..", "..", "problems", "fivebar-table2-best-gii.json")
    with ViewProcess(hapsyn, other) as view:
        ws = WebSocket(f"ws://127.0.0.1:{view.port}/live")
        answer = json.loads((ws.send(json.dumps({"t": 0, "position": [0, 0, 0], "orientation": [1, 0, 0, 0]})), ws.receive())[1])
        ws.close()
        check(answer.get("error") == "live: the study's scene is not a motion scene: live frames need its frames and filter",
              f"a five-bar study's /live: {answer.get('error')!r}")
        view.stop()
    with open(problem) as f:
        doc = json.load(f)
    doc["objectives"] = doc["objectives"][:1]  # share "reachable": no rates or dynamics asked for
    doc["scene"]["options"]["path"] = os.path.abspath(os.path.join(HERE, "..", "..", "share", "motion", "synthetic", "csv",
                                                                    "S01", "drinking.csv"))
    reduced = os.path.join(work, "reachable-only.json")
    with open(reduced, "w") as f:
        json.dump(doc, f)
    with ViewProcess(hapsyn, reduced) as view:
        replay = get_json(view.url + "api/replay")
        view.stop()
    check(replay["ratios_missing"].startswith("the study's metrics do not ask the mechanism for the joint rates") and
          all(v is None for v in replay["qdot_ratio"] + replay["tau_ratio"]) and
          any(v is not None for v in replay["q"]),
          "a reachable-share study's replay: joint values, no bars, and why")


def main():
    hapsyn, problem, work = sys.argv[1:4]
    socket_only = "--socket-only" in sys.argv[4:]
    os.makedirs(work, exist_ok=True)
    if socket_only:
        stamps, shoulder = recording_poses()
        ik = None
    else:
        import hapsyn as module
        study = module.load(problem)
        shoulder = study.scene.attributes["shoulder_pose"]
        stamps = study.scene.attributes["time"].reshape(-1)
        ik = study.evaluate({}, samples=True, quantities=["joint_velocity"])["quantities"]["q"]
    # The first trajectory's first poses (the scene's order is time order within a recording).
    count = 0
    while count + 1 < len(stamps) and stamps[count + 1] > stamps[count] and count < 80:
        count += 1
    samples = list(range(count))

    with ViewProcess(hapsyn, problem) as view:
        port = view.port
        live = f"ws://127.0.0.1:{port}/live"
        replay = get_json(view.url + "api/replay")
        J = replay["joints"]
        frame_of = {s: f for f, s in enumerate(replay["sample"])}

        # Poses -> frames: joint angles of the IK and of the replay.
        ws = WebSocket(live)
        bad_ik, bad_replay, rates_from, last = [], [], None, None
        for i in samples:
            frame = json.loads((ws.send(message(stamps[i], shoulder[i])), ws.receive())[1])
            last = frame
            if frame.get("status") != "reachable" or frame.get("q") is None:
                bad_ik.append(i)
                continue
            if len(frame["q"]) != J:
                bad_ik.append(i)
                continue
            if socket_only:
                pass  # raw rows are not the scene's filtered poses: nothing to compare with
            else:
                if any(abs(frame["q"][j] - ik[i][j]) > 1e-9 for j in range(J)):
                    bad_ik.append(i)
                f = frame_of[i]
                if any(abs(frame["q"][j] - replay["q"][f * J + j]) > 1e-9 for j in range(J)):
                    bad_replay.append(i)
            if rates_from is None and frame["qdot_ratio"] is not None:
                rates_from = i
        if socket_only:
            check(not bad_ik, f"{len(samples)} raw poses: reachable frames with {J} joint angles ({len(bad_ik)} not)")
        else:
            check(not bad_ik, f"{len(samples)} poses: joint angles = the IK's (Python module) ({len(bad_ik)} differ)")
            check(not bad_replay, f"joint angles = the replay's for the same samples ({len(bad_replay)} differ)")
        check(rates_from is not None and 3 <= rates_from <= 40 and last["feasible"] in (0, 1) and
              len(last["tau_ratio"]) == J and "filtered over the last" in last["rates"],
              f"bars from pose {rates_from} on (the filter's minimum), feasibility {last['feasible']}: {last['rates']}")

        # A tracker's jittering time stamps (a shipped recording with clock jitter): resampled
        # to the stream's median rate before the filter, as the scene resamples a recording.
        from stream_recording import read_recording
        jitter = read_recording(os.path.join(HERE, "..", "..", "share", "motion", "synthetic", "csv", "S05", "side_reach.csv"))
        other = WebSocket(live)
        for t_j, p_j, o_j in jitter[:40]:
            other.send(json.dumps({"t": t_j, "position": p_j, "orientation": o_j}))
            jittered = json.loads(other.receive())
        other.close()
        check(jittered.get("rates", "").endswith("(resampled)") and jittered.get("tau_ratio") is not None,
              f"jittering time stamps: {jittered.get('rates')}")

        # Bad messages: an error frame each, the connection keeps working.
        t = float(stamps[samples[-1]]) + 1.0
        good = message(t, shoulder[0])
        bad = [
            ("not JSON", "nonsense", "live: the message is not JSON"),
            ("an array", "[1, 2]", "live: the message = [1,2]: must be a JSON object"),
            ("a missing key", json.dumps({"t": t, "position": [0, 0, 0]}), "live: message.orientation: missing"),
            ("a short position", json.dumps({"t": t, "position": [0, 0], "orientation": [1, 0, 0, 0]}),
             "live: message.position = [0,0]: must be [x, y, z] [m]"),
            ("a text coordinate", json.dumps({"t": t, "position": [0, "a", 0], "orientation": [1, 0, 0, 0]}),
             "live: message.position = [0,\"a\",0]: must be 3 finite numbers [m]"),
            ("a quaternion of norm 2", json.dumps({"t": t, "position": [0, 0, 0], "orientation": [2, 0, 0, 0]}),
             "live: message.orientation = [2,0,0,0]: a quaternion's norm must be 1 within 1e-3"),
            ("a sheared matrix", json.dumps({"t": t, "position": [0, 0, 0], "orientation": [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]}),
             "live: message.orientation = [[1,0.1,0],[0,1,0],[0,0,1]]: a rotation matrix must be orthonormal within 1e-4"),
            ("a text time", json.dumps({"t": "soon", "position": [0, 0, 0], "orientation": [1, 0, 0, 0]}),
             "live: message.t = \"soon\": must be a finite number [s]"),
            ("a text quaternion component", json.dumps({"t": t, "position": [0, 0, 0], "orientation": [1, 0, "0", 0]}),
             "live: message.orientation = [1,0,\"0\",0]: must be a unit quaternion"),
            ("a path", json.dumps({"t": t, "position": [0, 0, 0], "orientation": [1, 0, 0, 0], "file": "/etc/passwd"}),
             "live: message.file = \"/etc/passwd\": unknown key (known: t, position, orientation)"),
            ("an earlier time", message(float(stamps[0]), shoulder[0]),
             f"live: message.t = {float(stamps[0]):g} after "),
            ("5000 bytes", " " * 5000, "view: a message of 5000 bytes: more than the 4096 a message may have"),
        ]
        for what, text, expected in bad:
            answer = json.loads((ws.send(text), ws.receive())[1])
            check(answer.get("error", "").startswith(expected), f"{what}: error frame {answer.get('error')!r}")
        ws.send_frame(0x2, b"\x00\x01")
        answer = json.loads(ws.receive())
        check(answer.get("error") == "view: a binary message: send JSON text", f"binary: {answer.get('error')!r}")
        frame = json.loads((ws.send(good), ws.receive())[1])
        check(frame.get("q") is not None and "error" not in frame, "after the bad messages a good one gets its frame")
        ws.close()

        big = WebSocket(live)
        try:
            # The server may close (1009) while the 2 MiB are still being sent: then the send
            # itself fails (a broken pipe or a reset), which is the same refusal seen earlier.
            big.send("x" * (2 << 20))
            big.receive()
            closed = False
        except (ConnectionError, OSError) as e:
            closed = "1009" in str(e) or isinstance(e, OSError)
        check(closed, "a message beyond the 1 MiB limit closes its connection (1009)")
        again = WebSocket(live)
        frame = json.loads((again.send(message(stamps[0], shoulder[0])), again.receive())[1])
        check(frame.get("q") is not None, "the server keeps working after it")
        again.close()

        if socket_only:
            check_other_studies(hapsyn, problem, work)
        check(" 403 " in upgrade_status(port, "/live", host="evil.example:80") + " ", "foreign Host: 403")
        check(" 403 " in upgrade_status(port, "/live", origin="http://evil.example") + " ", "foreign Origin: 403")
        check(" 101 " in upgrade_status(port, "/live", origin=f"http://127.0.0.1:{port}") + " ", "the page's Origin: 101")
        check(" 404 " in upgrade_status(port, "/live/other") + " ", "another target: 404")

        watcher = WebSocket(f"ws://127.0.0.1:{port}/live/watch")
        sender = WebSocket(live)
        time.sleep(0.2)
        sent = (sender.send(message(stamps[0], shoulder[0])), sender.receive())[1]
        check(watcher.receive() == sent, "a watcher gets the frame the sender got")
        watcher.send("{}")
        check(json.loads(watcher.receive()).get("error", "").startswith("view: /live/watch only sends frames"),
              "a watcher's message gets an error frame")
        watcher.close()
        sender.close()

        if socket_only:
            check_stops(view)
            return finish()
        if browser_missing():
            return 1
        with chromium() as driver:
            driver.set_page_load_timeout(60)
            driver.get(view.url)
            wait_for(driver, bool, 60, script="return !!(window.hapsynView.replay || {}).ready", poll=0.3)
            before = driver.execute_script("return window.hapsynView.replay.q")
            driver.execute_script("window.hapsynView.live.start()")
            wait_for(driver, bool, 20, script="return window.hapsynView.live.connected", poll=0.1)
            check(driver.execute_script("return window.hapsynView.live.connected"), "the page watches /live/watch")
            bridge = WebSocket(live)
            pick = samples[len(samples) // 2:]
            frames = [json.loads((bridge.send(message(stamps[i], shoulder[i])), bridge.receive())[1]) for i in pick]
            bridge.close()
            state = wait_for(driver, lambda live: live.get("frames", 0) >= len(frames), 20,
                             script="return JSON.parse(JSON.stringify(window.hapsynView.live))")
            last = frames[-1]
            tip = last["segments"][-1]["points"][-1]
            check(state.get("frames") == len(frames), f"the page drew {state.get('frames')} live frames of {len(frames)}")
            check(state.get("q") == last["q"] and state.get("q") != before,
                  f"the page's arm is at the last pose's joint angles {['%.3f' % v for v in last['q']]}")
            check(state.get("tip") is not None and all(abs(a - b) < 1e-6 for a, b in zip(state["tip"], tip)),
                  f"the drawn tip {state.get('tip')} = the frame's {tip}")
            # WebXR's path without a headset: a controller pose relative to the user's shoulder is
            # the palm pose in S; the frame equals the bridge's for that pose, and the study
            # placed around the user puts the end-effector target at the controller.
            shoulder_xr = driver.execute_script("return window.hapsynView.xr.shoulder")
            i = pick[-1]
            controller = [shoulder_xr[k] + float(shoulder[i][k]) for k in range(3)]
            orientation = [float(v) for v in shoulder[i][3:7]]
            xr_frame = driver.execute_async_script(
                "const [t, p, q, done] = arguments; window.hapsynView.xr.send(t, p, q).then(done);",
                1.0, controller, orientation)
            check(xr_frame and xr_frame.get("q") is not None and
                  all(abs(a - b) <= 1e-9 for a, b in zip(xr_frame["q"], last["q"])),
                  "WebXR: a controller pose at the shoulder + the palm position gives the bridge's joint angles")
            placed = driver.execute_script("return window.hapsynView.xr.baseToXr(arguments[0])", xr_frame["position"])
            check(all(abs(a - b) <= 1e-9 for a, b in zip(placed, controller)),
                  f"WebXR: the end-effector target placed in the headset's space {placed} = the controller {controller}")
            print(f"     WebXR session supported in this browser: {driver.execute_script('return window.hapsynView.xr.supported')}")
            screenshot(driver, os.path.join(work, "live.png"))
        check_stops(view)
    return finish()


if __name__ == "__main__":
    sys.exit(main())
