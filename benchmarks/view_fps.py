#!/usr/bin/env python3
"""Frames per second of `hapsyn view`'s page in headless Chromium (Debian's, WebGL on SwiftShader:
the CPU renders), for a study's point cloud; by default the paper's 34,548-pose human-arm
workspace (problems/haptic6r-evaluate.json). The page's own animation loop renders the scene
every animation frame; this counts the frames the browser delivers over a few seconds after the
page is ready, while the camera orbits (so nothing is cached), and prints the point count, the
frame rate and the frame times (median, 95th percentile).

Usage: /usr/bin/python3 benchmarks/view_fps.py [--hapsyn build/bin/hapsyn] [--problem FILE]
       [--seconds 5] [--window 1000x700]
Needs chromium, chromium-driver and python3-selenium (scripts/setup.sh --browser).
"""
import argparse
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "view"))

from view_process import ViewProcess  # noqa: E402

MEASURE = """
const seconds = arguments[0], done = arguments[arguments.length - 1];
const times = [];
const start = performance.now();
function frame(now) {
  times.push(now);
  if (now - start < seconds * 1000) requestAnimationFrame(frame);
  else {
    const dt = [];
    for (let i = 1; i < times.length; ++i) dt.push(times[i] - times[i - 1]);
    dt.sort((a, b) => a - b);
    done({frames: times.length - 1, elapsed: (times[times.length - 1] - times[0]) / 1000,
          median: dt[Math.floor(dt.length / 2)], p95: dt[Math.floor(dt.length * 0.95)]});
  }
}
requestAnimationFrame(frame);
"""

# Orbit: drag on the canvas with synthetic pointer events the OrbitControls listen to.
ORBIT = """
const canvas = document.querySelector('#view canvas');
const r = canvas.getBoundingClientRect();
let x = r.left + r.width / 2, y = r.top + r.height / 2;
const opts = (px, py) => ({clientX: px, clientY: py, pointerId: 1, pointerType: 'mouse', button: 0, buttons: 1, bubbles: true});
canvas.dispatchEvent(new PointerEvent('pointerdown', opts(x, y)));
window.__orbit = setInterval(() => { x += 3; canvas.ownerDocument.dispatchEvent(new PointerEvent('pointermove', opts(x, y))); }, 16);
"""


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    root = os.path.join(HERE, "..")
    parser.add_argument("--hapsyn", default=os.path.join(root, "build", "bin", "hapsyn"))
    parser.add_argument("--problem", default=os.path.join(root, "problems", "haptic6r-evaluate.json"))
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--window", default="1000x700")
    args = parser.parse_args()

    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    for flag in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", f"--window-size={args.window.replace('x', ',')}",
                 "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"):
        options.add_argument(flag)
    options.binary_location = "/usr/bin/chromium"
    with ViewProcess(args.hapsyn, args.problem, timeout=600) as view:
        driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
        try:
            driver.set_script_timeout(args.seconds + 60)
            driver.get(view.url)
            deadline = time.time() + 120
            while time.time() < deadline and not driver.execute_script("return (window.hapsynView || {}).ready"):
                time.sleep(0.2)
            points = driver.execute_script("return window.hapsynView.pointCount")
            driver.execute_script(ORBIT)
            r = driver.execute_async_script(MEASURE, args.seconds)
            driver.execute_script("clearInterval(window.__orbit)")
        finally:
            driver.quit()
        view.stop()
    fps = r["frames"] / r["elapsed"] if r["elapsed"] > 0 else 0.0
    print(f"{points} points, window {args.window}: {fps:.1f} frames/s over {r['elapsed']:.1f} s "
          f"(frame time median {r['median']:.1f} ms, 95th percentile {r['p95']:.1f} ms)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
