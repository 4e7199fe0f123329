"""Shared fixtures: where the build tree, the sources and the test plugins are.

CTest (python/CMakeLists.txt) sets HAPSYN_BINARY_DIR, HAPSYN_SOURCE_DIR and
HAPSYN_PYTHON_TEST_PLUGIN_DIR and puts <build>/python on PYTHONPATH; run by hand, the defaults
are the repository's build/ directory.
"""
import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("HAPSYN_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
BINARY_DIR = pathlib.Path(os.environ.get("HAPSYN_BINARY_DIR", SOURCE_DIR / "build"))
TEST_PLUGIN_DIR = pathlib.Path(os.environ.get("HAPSYN_PYTHON_TEST_PLUGIN_DIR", BINARY_DIR / "python" / "test-plugins"))
PROBLEMS = SOURCE_DIR / "problems"
CLI = BINARY_DIR / "bin" / "hapsyn"

import hapsyn  # noqa: E402  (after the paths, so that a failing import names them in the log)


def cli(*args, check=True):
    """Runs the build tree's hapsyn program; returns (exit code, stdout, stderr)."""
    p = subprocess.run([str(CLI), *map(str, args)], capture_output=True, text=True, timeout=600)
    if check and p.returncode != 0:
        raise AssertionError(f"hapsyn {' '.join(map(str, args))} failed ({p.returncode}): {p.stderr}")
    return p.returncode, p.stdout, p.stderr


def cli_error(*args):
    """The CLI's error message for a failing command (the text after 'hapsyn: error: ')."""
    code, _, err = cli(*args, check=False)
    assert code == 1, f"expected exit code 1, got {code}: {err}"
    line = err.strip().splitlines()[-1]
    prefix = "hapsyn: error: "
    assert line.startswith(prefix), err
    return line[len(prefix):]


def cli_run(problem, out_dir, *sets):
    args = ["run", problem, "--out", out_dir, "--quiet"]
    for s in sets:
        args += ["--set", s]
    cli(*args)
    with open(pathlib.Path(out_dir) / "result.json") as f:
        return json.load(f)


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


class PyMeanIsotropy:
    """The Python twin of examples/mean_isotropy (the C++ plugin "mean_isotropy")."""

    locals = [("isotropy", "sum", ""), ("reachable", "sum", "")]
    needs = ["jacobian"]

    def __init__(self, exponent=1.0):
        self.exponent = float(exponent)
        self.calls = 0
        self.samples_seen = 0

    def local_batch(self, q):
        self.calls += 1
        n = q["status"].shape[0]
        self.samples_seen += n
        out = np.zeros((n, 2))
        ok = q["status"] == 0
        if ok.any():
            s = np.linalg.svd(q["jacobian"][ok], compute_uv=False)
            ratio = np.clip(np.where(s[:, 0] > 0, s[:, -1] / np.where(s[:, 0] > 0, s[:, 0], 1.0), 0.0), 0.0, 1.0)
            out[ok, 0] = ratio if self.exponent == 1.0 else ratio ** self.exponent
            out[ok, 1] = 1.0
        return out

    def combine(self, reduced, samples):
        return float(reduced[0] / reduced[1]) if reduced[1] > 0 else 0.0


class PyGII:
    """A Python twin of the worst-case GII: min sigma_min(J) over max sigma_max(J)."""

    locals = [("sigma_min", "min", ""), ("sigma_max", "max", "")]
    needs = ["jacobian"]

    def local_batch(self, q):
        s = np.linalg.svd(q["jacobian"], compute_uv=False)
        return np.stack([s[:, -1], s[:, 0]], axis=1)

    def combine(self, reduced, samples):
        return float(reduced[0] / reduced[1])


@pytest.fixture
def plugin_dir():
    assert (TEST_PLUGIN_DIR / "hapsyn-mean_isotropy.so").exists(), f"missing test plugin in {TEST_PLUGIN_DIR}"
    return TEST_PLUGIN_DIR
