"""What the browser tests of `hapsyn view` share (tests/view/*_test.py): the check list, the study
run, headless Chromium, waiting for the page's state, counting a canvas' colours, screenshots and
stopping the server. One place, so that every script checks these the same way."""
import contextlib
import json
import os
import shutil
import subprocess
import time
import urllib.request

CHROMEDRIVER = "/usr/bin/chromedriver"
# Distinct colours a rendered view has at least (background, grid of points in a colour ramp,
# links, axes); a blank or failed canvas has 1 or 2.
MIN_COLOURS = 50
# The page's state (window.hapsynView) as plain JSON; {} before app.js has set it.
STATE = "return JSON.parse(JSON.stringify(window.hapsynView || {}))"
# Flags every test's Chromium gets: headless, a fixed window, WebGL in software (SwiftShader).
CHROMIUM_FLAGS = ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=1000,700",
                  "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist")

failures = []


def check(condition, what):
    """Prints 'ok   what' or 'FAIL what'; a failure is kept for finish()."""
    print(("ok   " if condition else "FAIL ") + what, flush=True)
    if not condition:
        failures.append(what)


def finish():
    """Prints the failure count; the script's exit code (1 when any check failed)."""
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


def browser_missing():
    """Whether chromium or chromedriver is missing (then says so as a failure, with the fix)."""
    for need in ("chromium", CHROMEDRIVER):
        if not shutil.which(need):
            print(f"FAIL {need} is not installed: bash scripts/setup.sh --browser")
            return True
    return False


def set_options(values):
    """Command-line `path=value` arguments as `hapsyn run`'s --set options."""
    return [a for s in values for a in ("--set", s)]


def run_study(hapsyn, problem, out, sets=()):
    """`hapsyn run PROBLEM --out OUT --quiet SETS...` into a fresh OUT; its result.json."""
    shutil.rmtree(out, ignore_errors=True)
    subprocess.run([hapsyn, "run", problem, "--out", out, "--quiet", *sets], check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "result.json")) as f:
        return json.load(f)


def prepare_study(args):
    """For a script's `HAPSYN PROBLEM_FILE WORK_DIR [path=value ...]` (args, sys.argv[1:]): makes
    WORK_DIR and runs the study into WORK_DIR/run with the path=value as --set options; (hapsyn,
    problem, work, run, result.json). None when Chromium or chromedriver is missing (said as a
    failure), before anything runs."""
    hapsyn, problem, work = args[:3]
    os.makedirs(work, exist_ok=True)
    if browser_missing():
        return None
    run = os.path.join(work, "run")
    return hapsyn, problem, work, run, run_study(hapsyn, problem, run, set_options(args[3:]))


def get_json(url, timeout=60):
    """The JSON document a GET of url answers."""
    with urllib.request.urlopen(url, timeout=timeout) as response:
        return json.load(response)


def browser(*extra_flags):
    """Headless Chromium (Debian's) through chromedriver, with CHROMIUM_FLAGS and extra_flags."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    for flag in CHROMIUM_FLAGS + extra_flags:
        options.add_argument(flag)
    options.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
    return webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)


def offline_browser():
    """browser() without a network: every host name fails to resolve, any proxy use goes nowhere,
    and http(s)/ws(s) requests are blocked; file:// pages may read other files."""
    driver = browser("--host-resolver-rules=MAP * ~NOTFOUND", "--proxy-server=127.0.0.1:9",
                     "--allow-file-access-from-files")
    driver.execute_cdp_cmd("Network.enable", {})
    driver.execute_cdp_cmd("Network.setBlockedURLs", {"urls": ["http://*", "https://*", "ws://*", "wss://*"]})
    return driver


@contextlib.contextmanager
def chromium(offline=False):
    """browser() (offline: offline_browser()) for a with block; it quits at the block's end."""
    driver = offline_browser() if offline else browser()
    try:
        yield driver
    finally:
        driver.quit()


def page_state(driver):
    """window.hapsynView now, as plain JSON."""
    return driver.execute_script(STATE)


def wait_for(driver, done, timeout=30, script=STATE, poll=0.2):
    """Runs script every poll seconds until done(its answer) or timeout; the last answer."""
    deadline = time.time() + timeout
    state = {}
    while time.time() < deadline:
        state = driver.execute_script(script)
        if done(state):
            break
        time.sleep(poll)
    return state


def wait_state(driver, key, timeout=30):
    """The page's state once state[key] is truthy or it reports an error (or at timeout)."""
    return wait_for(driver, lambda state: state.get(key) or state.get("error"), timeout)


def open_page(driver, url, what="page ready", timeout=30, done=None):
    """Loads url, waits until the page is ready (or done(state)) or fails, and checks it is
    ready without an error; the page's state."""
    driver.set_page_load_timeout(timeout)
    driver.get(url)
    state = wait_state(driver, "ready", timeout) if done is None else wait_for(driver, done, timeout)
    check(state.get("ready") is True and not state.get("error"), f"{what} (error: {state.get('error')})")
    return state


def count_colours(driver, selector="#view canvas"):
    """The distinct RGB colours of the canvas at selector (copied into a 2D canvas)."""
    return driver.execute_script("""
const source = document.querySelector(arguments[0]);
const copy = document.createElement('canvas');
copy.width = source.width; copy.height = source.height;
const context = copy.getContext('2d');
context.drawImage(source, 0, 0);
const data = context.getImageData(0, 0, copy.width, copy.height).data;
const seen = new Set();
for (let i = 0; i < data.length; i += 4) seen.add((data[i] << 16) | (data[i + 1] << 8) | data[i + 2]);
return seen.size;
""", selector)


def check_not_blank(driver, what="canvas not blank", selector="#view canvas", least=MIN_COLOURS):
    """Checks the canvas at selector has more than `least` distinct colours."""
    colours = count_colours(driver, selector)
    check(colours > least, f"{what}: {colours} distinct colours (> {least})")


def click_at(driver, x, y):
    """A real mouse click at client pixel (x, y)."""
    from selenium.webdriver.common.actions.action_builder import ActionBuilder
    actions = ActionBuilder(driver)
    actions.pointer_action.move_to_location(int(round(x)), int(round(y)))
    actions.pointer_action.click()
    actions.perform()


def screenshot(driver, path):
    """Saves the window to path and checks the PNG is not trivially small (> 10 kB)."""
    driver.save_screenshot(path)
    check(os.path.getsize(path) > 10000, f"screenshot {path}")


def check_stops(view, what="the server stops with exit 0"):
    """Stops a ViewProcess (SIGINT) and checks it exits 0."""
    code, _ = view.stop()
    check(code == 0, what)
