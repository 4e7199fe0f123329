#!/usr/bin/env python3
"""CTest Python.PipInstallIntoFreshVenv: `pip install .` of hapsyn into a fresh virtual environment.

What a user does with a clone, with nothing but Debian's packages (no index, no build isolation):

    python3 -m venv --system-site-packages VENV
    VENV/bin/pip install --no-build-isolation --no-index .

1. The source tree is copied as a clone of it would be: the files git lists (tracked, plus new
   files that are not ignored) with their working-tree contents, so that uncommitted edits are
   tested too (a `git clone` would test HEAD, not the tree being worked on) and build/, results/
   and every other ignored file are left out as a fresh clone lacks them. The copy is a folder of
   its own kept between runs (--source-copy) and synchronised file by file with the timestamps
   kept, so that the CMake build directory (HAPSYN_PIP_BUILD_DIR, --build-dir), which CMake ties
   to one source path, is reused and a rerun only rebuilds what changed.
2. A fresh venv in a temporary directory; pip installs the copy into it.
3. From a temporary directory outside the source tree, with PYTHONPATH and HAPSYN_PLUGIN_PATH
   unset, the venv's python imports hapsyn and checks that the package, libhapsyn (as mapped into
   the process) and every plugin come from the venv, that every in-tree plugin is listed, and that
   a shipped study (problems/fivebar-gii-coarse.json, copied there) converges to a GII in (0, 1).

Any failure prints pip's output (kept in <work-dir>/pip-install.log). The time pip took is printed.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

MARKER = ".hapsyn-pip-test-source-copy"
STUDY = "problems/fivebar-gii-coarse.json"
CHAIN_STUDY = "problems/phantom3r-gii-box.json"  # reads share/serial_chain/phantom_3r.urdf


def fail(message: str, log: str = "") -> None:
    if log:
        print(log, end="" if log.endswith("\n") else "\n")
    print(f"pip_install_test: FAILED: {message}", flush=True)
    sys.exit(1)


def listed_files(source: Path):
    """The files of a clone of `source` with the working tree's contents (relative paths)."""
    try:
        out = subprocess.run(["git", "-C", str(source), "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                             check=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE).stdout
        names = [n for n in out.decode("utf-8", "surrogateescape").split("\0") if n]
    except (OSError, subprocess.CalledProcessError) as error:
        print(f"pip_install_test: not a git work tree ({error}); copying every file but build*/ and results/")
        names = [str(p.relative_to(source)) for p in source.rglob("*") if p.is_file() or p.is_symlink()]
        names = [n for n in names if not n.startswith(".git/")]
    top_excluded = re.compile(r"^(build[^/]*|results)/")
    # A tracked file deleted in the working tree is not there (os.path.lexists: a symlink counts).
    return sorted(n for n in names if not top_excluded.match(n) and os.path.lexists(source / n))


def synchronise(source: Path, copy: Path, names) -> int:
    """Makes `copy` hold exactly `names` from `source`; returns how many files were (re)copied."""
    if copy.exists() and not (copy / MARKER).exists():
        fail(f"{copy} exists and is not a copy made by this test (no {MARKER}); not touching it")
    copy.mkdir(parents=True, exist_ok=True)
    (copy / MARKER).touch()
    wanted = set(names) | {MARKER}
    changed = 0
    for name in names:
        src, dst = source / name, copy / name
        s = os.lstat(src)
        try:
            d = os.lstat(dst)
            same = (d.st_size == s.st_size and int(d.st_mtime) == int(s.st_mtime)
                    and os.path.islink(dst) == os.path.islink(src))
        except FileNotFoundError:
            same = False
        if not same:
            if os.path.lexists(dst) or dst.is_dir():
                shutil.rmtree(dst) if dst.is_dir() and not dst.is_symlink() else dst.unlink()
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dst, follow_symlinks=False)
            changed += 1
    # Whatever else is there (a file deleted since, pip's leftovers) goes.
    for root, dirs, files in os.walk(copy, topdown=False):
        for f in files:
            path = Path(root) / f
            if str(path.relative_to(copy)) not in wanted:
                path.unlink()
        for d in dirs:
            path = Path(root) / d
            if path.is_symlink():
                if str(path.relative_to(copy)) not in wanted:
                    path.unlink()
            elif not any(path.iterdir()):
                path.rmdir()
    return changed


def in_tree_plugins(source: Path):
    """Names of the plugins the source tree builds (hapsyn_add_plugin(<name> ...) under plugins/)."""
    names = set()
    for f in list(source.glob("plugins/**/CMakeLists.txt")) + list(source.glob("plugins/**/*.cmake")):
        names.update(re.findall(r"hapsyn_add_plugin\(\s*([A-Za-z0-9_]+)", f.read_text(errors="replace")))
    return sorted(names)


CHECK = r"""
import json, os, sys
from pathlib import Path
venv, expected, study_file, chain_file = Path(sys.argv[1]).resolve(), set(json.loads(sys.argv[2])), sys.argv[3], sys.argv[4]
for variable in ("PYTHONPATH", "HAPSYN_PLUGIN_PATH"):
    assert variable not in os.environ, variable + " is set"
import hapsyn
package = Path(hapsyn.__file__).resolve().parent
print("hapsyn", hapsyn.__version__, "from", package)
assert venv in package.parents, f"hapsyn imported from {package}, not from the venv {venv}"
maps = {line.split(None, 5)[5].strip() for line in open("/proc/self/maps") if "libhapsyn" in line and len(line.split(None, 5)) == 6}
assert maps, "libhapsyn is not mapped"
for path in maps:
    assert venv in Path(path).resolve().parents, f"libhapsyn loaded from {path}, not from the venv"
print("libhapsyn:", ", ".join(sorted(maps)))
plugins = hapsyn.plugins()
found = {p["name"] for p in plugins}
for p in plugins:
    assert venv in Path(p["file"]).resolve().parents, f"plugin {p['name']} loaded from {p['file']}"
    assert Path(p["file"]).parent == package / "lib" / "hapsyn" / "plugins", p["file"]
print(len(plugins), "plugins:", " ".join(sorted(found)))
missing, extra = sorted(expected - found), sorted(found - expected)
assert not missing, f"in-tree plugins not found in the venv: {missing}"
assert not extra, f"plugins that are not in the tree: {extra}"
study = hapsyn.load(study_file, set=["threads=2"])
result = study.run()
gii = result.best_objectives["gii"]
print(study_file, "->", result.status, result.best_objectives, result.best_design)
assert result.status == "converged", result.status
assert 0.0 < gii < 1.0, gii
# A study that reads a data file (the URDF in share/serial_chain) finds it in the package's
# share/hapsyn: the source tree's share/ is hidden while this runs (main() renames it).
chain = hapsyn.load(chain_file, set=['solver={"plugin": "evaluate"}', "design={}", "threads=2"])
chained = chain.run()
print(chain_file, "->", chained.status, chained.best_objectives)
assert chained.status == "converged", chained.status
assert 0.0 < chained.best_objectives["gii"] < 1.0, chained.best_objectives
print("ok")
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--source", required=True, type=Path, help="the source tree (a git work tree)")
    parser.add_argument("--work-dir", required=True, type=Path,
                        help="kept between runs: the source copy (source/) and pip's log")
    parser.add_argument("--build-dir", type=Path, help="HAPSYN_PIP_BUILD_DIR (default: <work-dir>/cmake-build)")
    parser.add_argument("--python", default=sys.executable, help="the interpreter the venv is made from")
    args = parser.parse_args()
    source = args.source.resolve()
    work = args.work_dir.resolve()
    copy = work / "source"
    build_dir = (args.build_dir or work / "cmake-build").resolve()
    log_file = work / "pip-install.log"

    names = listed_files(source)
    if "setup.py" not in names or "pyproject.toml" not in names:
        fail(f"{source} has no setup.py / pyproject.toml among its files")
    changed = synchronise(source, copy, names)
    print(f"source copy {copy}: {len(names)} files, {changed} copied")
    expected = in_tree_plugins(copy)
    if not expected:
        fail("no hapsyn_add_plugin() found under plugins/")

    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "PYTHONHOME", "HAPSYN_PLUGIN_PATH", "VIRTUAL_ENV")
           and not k.startswith("PIP_")}
    env.update(PYTHONNOUSERSITE="1", PIP_DISABLE_PIP_VERSION_CHECK="1", HAPSYN_PIP_BUILD_DIR=str(build_dir))
    env.setdefault("CMAKE_BUILD_PARALLEL_LEVEL", "2")

    with tempfile.TemporaryDirectory(prefix="hapsyn-pip-test-") as temp:
        temp = Path(temp)
        venv = temp / "venv"
        made = subprocess.run([args.python, "-m", "venv", "--system-site-packages", str(venv)], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if made.returncode != 0:
            fail(f"{args.python} -m venv failed (Debian: python3-venv)", made.stdout)
        python = venv / "bin" / "python"

        command = [str(python), "-m", "pip", "install", "-v", "--no-build-isolation", "--no-index", str(copy)]
        print("$", " ".join(command), f"(HAPSYN_PIP_BUILD_DIR={build_dir}, "
              f"CMAKE_BUILD_PARALLEL_LEVEL={env['CMAKE_BUILD_PARALLEL_LEVEL']})", flush=True)
        start = time.monotonic()
        pip = subprocess.run(command, env=env, cwd=str(temp), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             text=True, errors="replace")
        seconds = time.monotonic() - start
        work.mkdir(parents=True, exist_ok=True)
        log_file.write_text(pip.stdout)
        if pip.returncode != 0:
            fail(f"pip install exited with {pip.returncode} after {seconds:.0f} s (output above, also in {log_file})",
                 pip.stdout)
        steps = len(re.findall(r"^\s*\[\d+/\d+\] ", pip.stdout, flags=re.M))
        print(f"pip install: {seconds:.1f} s, {steps} build steps (log: {log_file})")

        run_dir = temp / "run"
        run_dir.mkdir()
        shutil.copy2(copy / STUDY, run_dir / Path(STUDY).name)
        shutil.copy2(copy / CHAIN_STUDY, run_dir / Path(CHAIN_STUDY).name)
        hidden = copy.parent / "share.hidden"
        shutil.rmtree(hidden, ignore_errors=True)  # left by a run that was killed here
        (copy / "share").rename(hidden)
        try:
            check = subprocess.run([str(python), "-c", CHECK, str(venv), json.dumps(expected), Path(STUDY).name,
                                    Path(CHAIN_STUDY).name],
                                   env=env, cwd=str(run_dir), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                   text=True, errors="replace")
        finally:
            hidden.rename(copy / "share")
        print(check.stdout, end="")
        if check.returncode != 0:
            fail("the installed package failed its checks (output above); pip's output follows", pip.stdout)
    print("pip_install_test: passed")


if __name__ == "__main__":
    main()
