#!/usr/bin/env python3
"""Checks the layering of the plugin API (what an author includes and links), from the sources.

  1. HAPSYN_PLUGIN_API_VERSION is 5 (4: the two layers; 5: MechanismModel::segments).
  2. No installed header under framework/include/hapsyn/ outside accel/ includes, directly or
     through other hapsyn headers, a vector, dispatch or block header (hapsyn/accel/...), nor a
     private framework header (hapsyn/internal/...).
  3. solver.hpp reaches neither the cluster header nor the evaluator's layout (accel/ headers).
  4. The culling plugin includes and links nothing of the grid plugin's folder.
  5. No plugin's library or plugin target links another plugin's library (shared engines live
     in plugins/<kind>/shared/, e.g. plugins/solvers/shared/ or the human arm model in
     plugins/scenes/shared/human_arm_model/, or in the framework), except the exceptions listed
     below with the reason.

Usage: check_plugin_api.py SOURCE_DIR. Exit 1 with one line per violation.
"""
import pathlib
import re
import sys

# Plugin libraries that link another plugin's library, with the reason. Each is a known debt.
ALLOWED_LINKS = {}

INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', re.M)


def hapsyn_includes(path):
    return [m for m in INCLUDE.findall(path.read_text()) if m.startswith("hapsyn/")]


def closure(root, header):
    """The hapsyn headers `header` reaches (itself excluded), as include names."""
    seen, todo = set(), [header]
    while todo:
        name = todo.pop()
        path = root / "framework/include" / name
        if not path.exists():
            continue  # a private header: reported by the caller, not followed
        for inc in hapsyn_includes(path):
            if inc not in seen:
                seen.add(inc)
                todo.append(inc)
    return seen


def main():
    root = pathlib.Path(sys.argv[1])
    problems = []
    plugin_hpp = (root / "framework/include/hapsyn/plugin.hpp").read_text()
    if not re.search(r"#define HAPSYN_PLUGIN_API_VERSION 5\b", plugin_hpp):
        problems.append("plugin.hpp: HAPSYN_PLUGIN_API_VERSION is not 5")

    include_dir = root / "framework/include/hapsyn"
    for header in sorted(include_dir.glob("*.hpp")):
        name = "hapsyn/" + header.name
        for inc in sorted(closure(root, name)):
            if inc.startswith("hapsyn/accel/"):
                problems.append(f"{name} reaches {inc}: the author's layer must not include the acceleration layer")
            if inc.startswith("hapsyn/internal/"):
                problems.append(f"{name} reaches {inc}: an installed header includes a private one")
    solver = closure(root, "hapsyn/solver.hpp")
    if "hapsyn/cluster.hpp" in solver:
        problems.append("hapsyn/solver.hpp reaches hapsyn/cluster.hpp")

    culling = root / "plugins/solvers/culling"
    for path in sorted(culling.rglob("*")):
        if path.suffix in (".cpp", ".hpp"):
            for inc in INCLUDE.findall(path.read_text()):
                if "grid/" in inc:
                    problems.append(f"{path.relative_to(root)} includes {inc} from the grid plugin")
        if path.name == "CMakeLists.txt" and "hapsyn_grid_model" in path.read_text():
            problems.append(f"{path.relative_to(root)} links the grid plugin's library")

    plugin_dirs = {p.name: p for p in root.glob("plugins/*/*") if p.is_dir() and p.name != "shared"}
    link = re.compile(r"target_link_libraries\(\s*(hapsyn_(\w+?)_model)\b([^)]*)\)", re.S)
    add_plugin = re.compile(r"hapsyn_add_plugin\(\s*(\w+)([^)]*)\)", re.S)
    for name, folder in sorted(plugin_dirs.items()):
        for cmake in sorted(list(folder.glob("CMakeLists.txt")) + list(folder.glob("*.cmake"))):
            text = cmake.read_text()
            uses = [(m.group(2), m.group(3)) for m in link.finditer(text)]
            uses += [(m.group(1), m.group(2)) for m in add_plugin.finditer(text)]
            for owner, args in uses:
                for other in re.findall(r"\bhapsyn_(\w+?)_model\b", args):
                    if other != owner and other in plugin_dirs and (owner, other) not in ALLOWED_LINKS:
                        problems.append(f"{cmake.relative_to(root)}: the {owner} plugin links the {other} plugin's library")

    for p in problems:
        print(p)
    print(f"check_plugin_api: {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
