#!/usr/bin/env python3
"""Runs a tutorial's commands as written (ctest Docs.Tutorial.<page>, Docs.TutorialNotebook).

A page under docs/tutorials/ is run block by block: every ```sh block, in order, in one bash
(`set -euo pipefail`) started in a scratch directory that looks like the repository root
(build/, problems/, share/, examples/, docs/ and scripts/ linked in). A ```text block that
follows a ```sh block (before the next one) is that command's expected output: each of its
lines must appear in what the block printed, in order; "..." in an expected line stands for
any text (timings, counts that vary). So a tutorial cannot drift from the program: a command
that fails, or prints something else than the page says, fails the test.

A notebook (--notebook) is executed with nbconvert in the same kind of scratch directory, and
every cell's text output must equal the output stored in the notebook: the page a reader opens
shows what the program prints today.

    python3 tests/docs/run_tutorials.py --build build docs/tutorials/first-study.md
    python3 tests/docs/run_tutorials.py --build build --notebook docs/tutorials/python.ipynb
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[2]
LINKED = ("problems", "share", "examples", "docs", "scripts", "python")
MARK = "@@hapsyn-tutorial-block {}@@"


def blocks(page: Path) -> list:
    """[(language, text, first line number)] of the page's fenced blocks."""
    out, language, lines, start = [], None, [], 0
    for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
        fence = re.match(r"^```(\w*)\s*$", line)
        if fence and language is None:
            language, lines, start = fence.group(1) or "text", [], number
        elif line.strip() == "```" and language is not None:
            out.append((language, "\n".join(lines), start))
            language = None
        elif language is not None:
            lines.append(line)
    return out


def commands_and_expectations(page: Path) -> list:
    """[(command text, expected output or None, line)]: each sh block with the text block after it."""
    steps = []
    for language, text, line in blocks(page):
        if language in ("sh", "bash"):
            steps.append([text, None, line])
        elif language == "text" and steps and steps[-1][1] is None:
            steps[-1][1] = text
    return steps


def scratch(build: Path) -> Path:
    work = Path(tempfile.mkdtemp(prefix="hapsyn-tutorial-"))
    (work / "build").symlink_to(build.resolve())
    for name in LINKED:
        (work / name).symlink_to(SOURCE / name)
    return work


def environment() -> dict:
    env = dict(os.environ, HAPSYN_PLUGIN_PATH="", PYTHONDONTWRITEBYTECODE="1")
    env.pop("PYTHONPATH", None)
    # Open MPI refuses root unless told: the tutorials' mpirun runs as the suite's user.
    env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMPI_MCA_rmaps_base_oversubscribe="1")
    return env


def expected_lines_found(expected: str, printed: str) -> list:
    """The expected lines not found, in order, in `printed` ("..." matches anything)."""
    actual = [" ".join(line.split()) for line in printed.splitlines()]
    missing, at = [], 0
    for want in expected.splitlines():
        want = " ".join(want.split())
        if not want:
            continue
        pattern = re.compile(".*".join(re.escape(piece.strip()) for piece in want.split("...")))
        for k in range(at, len(actual)):
            if pattern.search(actual[k]):
                at = k + 1
                break
        else:
            missing.append(want)
    return missing


def run_page(page: Path, build: Path, timeout: float) -> int:
    steps = commands_and_expectations(page)
    if not steps:
        print(f"{page}: no ```sh block: nothing a reader could run")
        return 1
    script = "set -euo pipefail\n" + "".join(f"echo '{MARK.format(k)}'\n{text}\n" for k, (text, _, _) in enumerate(steps))
    work = scratch(build)
    try:
        done = subprocess.run(["bash", "-c", script], cwd=work, env=environment(), stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        print(f"{page}: timed out after {timeout} s")
        return 1
    finally:
        keep = os.environ.get("HAPSYN_KEEP_TUTORIAL_DIR")
        if not keep:
            shutil.rmtree(work, ignore_errors=True)
    parts = re.split(r"^@@hapsyn-tutorial-block (\d+)@@$", done.stdout, flags=re.M)
    printed = {int(parts[i]): parts[i + 1] for i in range(1, len(parts) - 1, 2)}
    failures = 0
    if done.returncode != 0:
        last = max(printed) if printed else 0
        text, _, line = steps[last]
        print(f"{page}:{line}: this block failed (exit {done.returncode}):\n{text}\n--- it printed:\n{printed.get(last, done.stdout)}")
        return 1
    for k, (text, expected, line) in enumerate(steps):
        if expected is None:
            continue
        missing = expected_lines_found(expected, printed.get(k, ""))
        if missing:
            failures += 1
            print(f"{page}:{line}: the output the page shows is not what the command prints now.\n"
                  f"command:\n{text}\nnot found (in order):\n  " + "\n  ".join(missing) +
                  f"\n--- it printed:\n{printed.get(k, '')}")
    print(f"{page.name}: {len(steps)} command blocks ran, {sum(e is not None for _, e, _ in steps)} outputs checked, "
          f"{failures} differ")
    return 1 if failures else 0


def cell_texts(notebook: dict) -> list:
    """The text each code cell printed or returned, one string per cell."""
    out = []
    for cell in notebook["cells"]:
        if cell["cell_type"] != "code":
            continue
        text = ""
        for o in cell.get("outputs", []):
            if o["output_type"] == "stream":
                text += "".join(o["text"])
            elif o["output_type"] in ("execute_result", "display_data"):
                text += "".join(o.get("data", {}).get("text/plain", "")) + "\n"
            elif o["output_type"] == "error":
                text += f"ERROR {o['ename']}: {o['evalue']}\n"
        out.append(text)
    return out


def run_notebook(notebook: Path, build: Path, timeout: float) -> int:
    if shutil.which("jupyter") is None:
        print("jupyter is not installed: apt-get install jupyter-nbconvert python3-ipykernel (scripts/setup.sh does)")
        return 1
    work = scratch(build)
    try:
        target = work / notebook.name
        shutil.copy(notebook, target)
        env = environment()
        env["PYTHONPATH"] = str(work / "build" / "python")
        done = subprocess.run(["jupyter", "nbconvert", "--to", "notebook", "--execute", str(target), "--output",
                               "executed.ipynb", f"--ExecutePreprocessor.timeout={int(timeout)}",
                               "--ExecutePreprocessor.kernel_name=python3"],
                              cwd=work, env=env, capture_output=True, text=True, timeout=timeout + 60)
        if done.returncode != 0:
            print(f"{notebook}: nbconvert --execute failed ({done.returncode}):\n{done.stderr[-4000:]}")
            return 1
        fresh = cell_texts(json.loads((work / "executed.ipynb").read_text(encoding="utf-8")))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    stored = cell_texts(json.loads(notebook.read_text(encoding="utf-8")))
    differ = [k for k, (a, b) in enumerate(zip(stored, fresh)) if a != b]
    if len(stored) != len(fresh) or differ:
        for k in differ:
            print(f"{notebook}: code cell {k + 1} prints now:\n{fresh[k]}--- the notebook shows:\n{stored[k]}")
        print("Re-execute the notebook (jupyter nbconvert --execute --inplace, PYTHONPATH=build/python) if the change "
              "is right.")
        return 1
    print(f"{notebook.name}: {len(fresh)} code cells ran; every output equals the stored one")
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", required=True, help="the build tree (holds bin/hapsyn and python/)")
    parser.add_argument("--notebook", action="store_true", help="the pages are notebooks")
    parser.add_argument("--timeout", type=float, default=600.0)
    parser.add_argument("pages", nargs="+")
    args = parser.parse_args()
    status = 0
    for page in args.pages:
        path = Path(page).resolve()
        status |= (run_notebook if args.notebook else run_page)(path, Path(args.build), args.timeout)
    return status


if __name__ == "__main__":
    sys.exit(main())
