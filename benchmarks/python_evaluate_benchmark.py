#!/usr/bin/env python3
"""Cost of the Python binding against C++ (README, section Python; python/README.md).

1. Study.evaluate per-call overhead: the five-bar Unal 2008 Table 2 design (GII and GDI), evaluated
   through hapsyn.Study.evaluate and, as the baseline, by Problem::evaluate in a C++ loop (the
   same study object and scratch, timed inside the module: _hapsyn.StudyHandle.time_evaluate).
   Two scene sizes: 121 samples (10 mm) where the overhead shows, 10201 (1 mm, the paper's).
2. A metric written in Python: the twin of examples/mean_isotropy (python/tests/conftest.py)
   against the C++ plugin, per sample, over the same scene, one after the other.

Run from the repository root on a built tree (the C++ twin is built with the tests):
    PYTHONPATH=build/python /usr/bin/python3 benchmarks/python_evaluate_benchmark.py
"""
import json
import os
import pathlib
import platform
import sys
import time

import numpy as np

import hapsyn

ROOT = pathlib.Path(__file__).resolve().parents[1]
BUILD = pathlib.Path(os.environ.get("HAPSYN_BINARY_DIR", ROOT / "build"))
sys.path.insert(0, str(ROOT / "python" / "tests"))
from conftest import PyMeanIsotropy  # noqa: E402


def best_of(f, repeats, rounds=5):
    """Seconds per call of f, the best of `rounds` rounds of `repeats` calls."""
    best = float("inf")
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(repeats):
            f()
        best = min(best, (time.perf_counter() - t0) / repeats)
    return best


def cpp_time(study, design, repeats, rounds=5):
    return min(study._handle.time_evaluate(design, repeats) for _ in range(rounds))


def main():
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.machine())
    print(f"machine: {cpu}, {os.cpu_count()} cores; Python {platform.python_version()}, NumPy {np.__version__}")
    table2 = ROOT / "problems" / "fivebar-table2-best-gii.json"
    grid = ROOT / "problems" / "fivebar-gii-coarse.json"
    design = np.array([0.0004, 0.2997, 0.3000, 0.4196])
    print("\n1. Study.evaluate per call, Table 2 design (0.4, 299.7, 300.0, 419.6) mm, objectives GII and GDI")
    for step, repeats in (("0.01", 2000), ("0.001", 50)):
        study = hapsyn.load(grid, set=[f"scene.options.step={step}", 'objectives=[{"metric":"gii"},{"metric":"gdi"}]'])
        n = len(study.scene)
        c = cpp_time(study, design, repeats)
        p = best_of(lambda: study.evaluate(design), repeats)
        b = best_of(lambda: study.evaluate(design[None, :]), repeats)
        print(f"  {n:6d} samples: C++ {c * 1e6:9.2f} us | evaluate(1-D) {p * 1e6:9.2f} us (+{(p - c) * 1e6:6.2f} us, "
              f"x{p / c:5.2f}) | evaluate(2-D, 1 row) {b * 1e6:9.2f} us (+{(b - c) * 1e6:6.2f} us)")
    study = hapsyn.load(grid, set=["scene.options.step=0.01"])
    rows = np.tile(design, (1000, 1))
    per_row = best_of(lambda: study.evaluate(rows), 3) / 1000
    c = cpp_time(study, design, 2000)
    print(f"  batch of 1000 rows, 121 samples, GII only: {per_row * 1e6:.2f} us per design (C++ {c * 1e6:.2f} us)")

    print("\n2. Metric per sample: Python twin of mean_isotropy vs the C++ example plugin (evaluate solver)")
    plugin_dir = BUILD / "python" / "test-plugins"
    with open(ROOT / "examples" / "mean_isotropy" / "study.json") as f:
        problem = json.load(f)
    for step, repeats in (("0.01", 500), ("0.001", 20)):
        problem["scene"]["options"]["step"] = float(step)
        times = {}
        for name, metrics in (("mean_isotropy", {}), ("py_mean_isotropy", {"py_mean_isotropy": PyMeanIsotropy})):
            problem["objectives"] = [{"metric": name}]
            study = hapsyn.load(problem, plugin_path=plugin_dir, metrics=metrics)
            n = len(study.scene)
            times[name] = cpp_time(study, np.array([]), repeats) / n
        cpp, py = times["mean_isotropy"], times["py_mean_isotropy"]
        print(f"  {n:6d} samples: C++ metric {cpp * 1e9:8.1f} ns/sample | Python metric {py * 1e9:8.1f} ns/sample "
              f"(x{py / cpp:5.2f}; +{(py - cpp) * 1e9:7.1f} ns/sample, mechanism solve included in both)")


if __name__ == "__main__":
    main()
