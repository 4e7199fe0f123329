#!/usr/bin/env python3
"""The human-arm figures the docs quote equal what the shipped problems print now.

Runs each shipped study named below with the build tree's hapsyn into a scratch directory,
formats its result as the docs quote it, and checks that every quoting file holds that exact
text. A figure that changed (a model, a default, a convention) fails here with the old and the
new text, instead of living on in the README.

    python3 tests/docs/check_figures.py --hapsyn build/bin/hapsyn [--slow]

--slow adds the studies that take half a minute each (the URDF evaluation, the UR5-like GA).
"""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile

SOURCE = pathlib.Path(__file__).resolve().parents[2]


def run(hapsyn, problem, scratch):
    out = scratch / problem.replace(".json", "")
    command = [hapsyn, "run", str(SOURCE / "problems" / problem), "--force", "--threads", "2",
               "--set", f"output.directory={out}", "--set", "output.plots=false"]
    if json.loads((SOURCE / "problems" / problem).read_text())["scene"]["plugin"] == "human_arm":
        command += ["--set", f"scene.options.cache_directory={scratch / 'cache'}"]
    p = subprocess.run(command, cwd=SOURCE, capture_output=True, text=True, timeout=1800)
    if p.returncode != 0:
        sys.exit(f"check_figures: {' '.join(command)} failed ({p.returncode}):\n{p.stderr}")
    return json.loads((out / "result.json").read_text())


def objectives(result):
    return result["best"]["objectives"]


def coverage_line(result):
    o = objectives(result)
    return (f"J_x {o['J_x']:.3f}, J_v {o['J_v']:.3f}, J_a {o['J_a']:.3f}, J_f {o['J_f']:.3f}, "
            f"J {o['J_x'] + o['J_v'] + o['J_a'] + o['J_f']:.3f}")


def shares_row(label, result):
    table = result["groups"]["subject"]
    cells = []
    for share in ("reachable", "velocity", "acceleration"):
        cells.append(f"{100 * table['mean'][share]:.1f} % ({100 * table['std'][share]:.1f})")
    return f"| {label} | " + " | ".join(cells) + " |"


def ga_line(result):
    o = objectives(result)
    return f"J = {result['best']['score']:.4f} (J_x {o['J_x']:.3f}, J_v {o['J_v']:.3f}, J_a {o['J_a']:.3f}, J_f {o['J_f']:.3f})"


# The user guide: the README and its pages under docs/ (the design notes are checked apart).
GUIDE = ["the guide"]


def read_quoting(name: str) -> str:
    if name == "the design notes":  # docs/design.md and its pages, one per section
        return "\n".join(p.read_text() for p in [SOURCE / "docs" / "design.md"] + sorted((SOURCE / "docs" / "design").glob("*.md")))
    if name != "the guide":
        return (SOURCE / name).read_text()
    pages = [SOURCE / "README.md"] + sorted(p for p in (SOURCE / "docs").glob("*.md") if p.name != "design.md")
    return "\n".join(p.read_text() for p in pages)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hapsyn", required=True)
    parser.add_argument("--slow", action="store_true")
    args = parser.parse_args()
    quotes = []  # (what, text, files that must hold it)
    with tempfile.TemporaryDirectory(prefix="hapsyn-figures-") as tmp:
        scratch = pathlib.Path(tmp)
        evaluate = run(args.hapsyn, "haptic6r-evaluate.json", scratch)
        quotes.append(("haptic6r-evaluate.json", coverage_line(evaluate), GUIDE))
        for problem, label in (("haptic6r-motion-validation.json", "`haptic6r-evaluate.json`"),
                               ("haptic6r-motion-validation-ga.json", "the GA's choice")):
            row = shares_row(label, run(args.hapsyn, problem, scratch))
            quotes.append((problem, row, GUIDE + ["the design notes"]))
        quick = run(args.hapsyn, "haptic6r-ga-quick.json", scratch)
        quotes.append(("haptic6r-ga-quick.json", ga_line(quick), GUIDE))
        if args.slow:
            urdf = run(args.hapsyn, "haptic6r-urdf-evaluate.json", scratch)
            quotes.append(("haptic6r-urdf-evaluate.json", coverage_line(urdf), GUIDE))
            ur5 = run(args.hapsyn, "ur5like-coverage-ga.json", scratch)
            quotes.append(("ur5like-coverage-ga.json", coverage_line(ur5), GUIDE))
    failures = 0
    for what, text, files in quotes:
        for name in files:
            # A quote may wrap across lines: compare with runs of white space as one space.
            if text not in " ".join(read_quoting(name).split()):
                print(f"{name}: does not quote what {what} prints now:\n    {text}")
                failures += 1
    checked = sum(len(files) for _, _, files in quotes)
    print(f"{checked - failures} passed, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
