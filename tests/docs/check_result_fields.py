#!/usr/bin/env python3
"""result.json against its declaration (ctest Docs.ResultFieldsAreDeclared).

Runs shipped studies of every kind the declaration covers (grid with plots, a shard, a Pareto
front with a reference front and without one, a GA, grouped recorded motion) and checks each
result.json against the fields `hapsyn reference` declares (framework/src/result_fields.cpp, the
source of docs/reference/result-json.md):

1. every field written is declared, with a JSON type the declaration allows;
2. every field declared "always" is written by every run;
3. every declared field is written by at least one of these runs, except the few listed in
   NOT_EXERCISED with the reason.

So a field added to the writer without its line in the declaration, or a declared field the
writer dropped, fails here, and the reference page cannot describe a result.json that is not.
Standard library only.
"""
import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

# Declared fields these runs cannot produce on one machine without faults, with the reason.
NOT_EXERCISED = {
    "ranks": "needs mpirun with more than one rank (tests/mpi cover it)",
    "ranks.count": "needs mpirun",
    "ranks.hosts": "needs mpirun",
    "ranks.distributed": "needs mpirun",
    "output_errors": "needs a file system that refuses a write (tests/output_files_test.cpp)",
    "plot_message": "needs gnuplot missing or failing (tests/plot_test.cpp)",
    "machine.host": "present on every Linux run, but declared 'when known'",
}


def tokens(path: str) -> list:
    out = []
    for part in path.split("."):
        if part.endswith("[]"):
            out += [part[:-2], "[]"]
        else:
            out.append(part)
    return out


def matches(pattern: list, path: list) -> bool:
    if pattern and pattern[-1] == "**":
        head = pattern[:-1]
        return len(path) > len(head) and matches(head, path[:len(head)])
    if len(pattern) != len(path):
        return False
    return all(p == "*" and t != "[]" or p == t for p, t in zip(pattern, path))


def type_ok(declared: str, value) -> bool:
    allowed = set(declared.split("|"))
    if "any" in allowed:
        return True
    kind = ("null" if value is None else "boolean" if isinstance(value, bool) else "integer" if isinstance(value, int)
            else "number" if isinstance(value, float) else "string" if isinstance(value, str)
            else "array" if isinstance(value, list) else "object")
    return kind in allowed or (kind == "integer" and "number" in allowed)


def nodes(value, path=()):
    """(token path, value) of every field; arrays of objects are entered with the token []."""
    if isinstance(value, dict):
        for key, v in value.items():
            yield path + (key,), v
            yield from nodes(v, path + (key,))
    elif isinstance(value, list):
        for v in value:
            if isinstance(v, (dict, list)):
                yield from nodes(v, path + ("[]",))


def check(doc: dict, name: str, fields: list, seen: set) -> list:
    problems = []
    for path, value in nodes(doc):
        if path[-1] == "[]":
            continue  # an array's element: its fields are what is declared
        hits = [f for f in fields if matches(tokens(f["path"]), list(path))]
        if not hits:
            problems.append(f"{name}: {'.'.join(path)} is written but not declared in framework/src/result_fields.cpp")
            continue
        exact = [f for f in hits if not f["path"].endswith("**")] or hits
        if not any(type_ok(f["type"], value) for f in exact):
            problems.append(f"{name}: {'.'.join(path)} = {json.dumps(value)[:60]} is not of the declared type "
                            f"{exact[0]['type']}")
        seen.update(f["path"] for f in hits)
    for f in fields:
        if f["when"] == "always" and "*" not in f["path"] and "[]" not in f["path"]:
            parts, cursor = f["path"].split("."), doc
            for part in parts:
                cursor = cursor.get(part) if isinstance(cursor, dict) else None
            if cursor is None and not (isinstance(doc.get(parts[0]), dict) and parts[-1] in ("**",)):
                problems.append(f"{name}: {f['path']} is declared 'always' but missing")
    return problems


def run(hapsyn: str, source: Path, work: Path, problem: str, out: str, *extra) -> dict:
    command = [hapsyn, "run", str(source / "problems" / problem), "--out", str(work / out), "--threads", "2",
               "--seed", "1", "-q", *extra]
    done = subprocess.run(command, capture_output=True, text=True, cwd=work)
    if done.returncode != 0:
        sys.exit(f"check_result_fields: {' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    return json.loads((work / out / "result.json").read_text(encoding="utf-8"))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--hapsyn", required=True)
    parser.add_argument("--source", default=str(Path(__file__).resolve().parents[2]))
    args = parser.parse_args()
    args.hapsyn = str(Path(args.hapsyn).resolve())  # the runs start in a temporary directory
    source = Path(args.source)
    reference = subprocess.run([args.hapsyn, "reference"], capture_output=True, text=True, check=True)
    fields = json.loads(reference.stdout)["result_json"]
    work = Path(tempfile.mkdtemp(prefix="hapsyn-result-fields-"))
    try:
        plots = "output.plots=true"
        docs = {
            "grid with plots": run(args.hapsyn, source, work, "fivebar-gii-coarse.json", "grid", "--set", plots),
            "grid share 1/2": run(args.hapsyn, source, work, "fivebar-gii-coarse.json", "share", "--shard", "1/2"),
            "weighted sum, missing reference": run(
                args.hapsyn, source, work, "fivebar-pareto-weighted-sum.json", "ws", "--set", plots,
                "--set", f"indicators.reference_front={work / 'none' / 'result.json'}",
                "--set", "solver.options.count=4"),
            "ga": run(args.hapsyn, source, work, "fivebar-gii-ga-coarse.json", "ga", "--set", plots),
            "grouped motion": run(args.hapsyn, source, work, "haptic6r-motion-validation.json", "motion"),
            "serial chain": run(args.hapsyn, source, work, "phantom3r-gii-box.json", "chain"),
        }
        docs["nsga2 against a reference"] = run(
            args.hapsyn, source, work, "fivebar-pareto-nsga2.json", "nsga2", "--set", plots,
            "--set", "solver.options.generations=20", "--set", "solver.options.population=40",
            "--set", f"indicators.reference_front={work / 'ws' / 'result.json'}",
            "--set", "indicators.reference_point=[0,0]", "--set", 'design.l0={"value": 0.05}')
        docs["weighted sum against a reference"] = run(
            args.hapsyn, source, work, "fivebar-pareto-weighted-sum.json", "ws2", "--set", "solver.options.count=3",
            "--set", f"indicators.reference_front={work / 'ws' / 'result.json'}")
        # One design of the two-objective study (a best, no front) against that front.
        docs["one design against a reference"] = run(
            args.hapsyn, source, work, "fivebar-pareto-weighted-sum.json", "one", "--set", 'solver={"plugin": "evaluate"}',
            *[a for v, x in (("l0", 0.1), ("l1", 0.2), ("l2", 0.25), ("r", 0.3))
              for a in ("--set", f'design.{v}={{"value": {x}}}')],
            "--set", f"indicators.reference_front={work / 'ws' / 'result.json'}")
        problems, seen = [], set()
        for name, doc in docs.items():
            problems += check(doc, name, fields, seen)
        for f in fields:
            if f["path"] not in seen and f["path"] not in NOT_EXERCISED:
                problems.append(f"{f['path']}: declared but written by none of the runs ({', '.join(docs)})")
        for path in NOT_EXERCISED:
            if path not in {f["path"] for f in fields}:
                problems.append(f"NOT_EXERCISED names {path}, which is not declared")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    if problems:
        print("\n".join(problems))
        return 1
    print(f"result.json: {len(fields)} declared fields; {len(docs)} runs agree with the declaration")
    return 0


if __name__ == "__main__":
    sys.exit(main())
