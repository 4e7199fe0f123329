"""Attack classes of hapsyn's file surfaces and of its Python module (tests/attack/README.md):

  urdf    mutated URDF files of a small serial_chain study (share/serial_chain/phantom_3r.urdf)
  dh      mutated DH tables (share/serial_chain/haptic6r_dh.json)
  csv     point_list scene CSVs and motion-scene CSV recordings
  bvh     BVH motion recordings of the motion scene
  python  misuse of the Python module (metrics that re-enter, return wrong types, raise)
  shares  sharded runs (--shard i/N) and `hapsyn merge` of tampered shares

attack.py registers them (`generators(module)`): this module takes attack.py's helpers (run,
classify, Case, Outcome, ...) from the module object it is given instead of importing attack.py,
which runs as __main__ (an import would load a second copy). Every input is derived from
(seed, class, index) alone; fixed oracles come first in each generator, then random mutations.
Standard library only (the python class runs the build tree's module under /usr/bin/python3 or
the interpreter running attack.py).
"""
from __future__ import annotations

import json
import os
import random
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

A = None  # attack.py's module object, bound by generators()
CLASSES = ["urdf", "dh", "csv", "bvh", "python", "shares"]

ROOT = Path(__file__).resolve().parents[2]
SHARE = ROOT / "share"
PHANTOM_URDF = SHARE / "serial_chain" / "phantom_3r.urdf"
DH_FILE = SHARE / "serial_chain" / "haptic6r_dh.json"
POINTS_CSV = SHARE / "point_list" / "example_planar.csv"
MOTION_CSV = SHARE / "motion" / "synthetic" / "csv" / "S01" / "drinking.csv"
MOTION_BVH = SHARE / "motion" / "synthetic" / "bvh" / "S01" / "drinking.bvh"
MEAN_ISOTROPY_STUDY = ROOT / "examples" / "mean_isotropy" / "study.json"


def generators(attack_module) -> dict:
    global A
    A = attack_module
    return {"urdf": gen_urdf, "dh": gen_dh, "csv": gen_csv, "bvh": gen_bvh, "python": gen_python, "shares": gen_shares}


# ------------------------------------------------------------------------------------------------
# Shared helpers.

def generated(cls: str, seed: int, n: int, fixed: list, random_kinds: list, run, cause) -> list:
    """The cases of a class: the fixed kinds first, then kinds drawn from (seed, class)."""
    rng = random.Random(f"{seed}:{cls}")
    cases = []
    for i in range(n):
        kind = fixed[i] if i < len(fixed) else rng.choice(random_kinds)
        cases.append(A.Case(cls, i, kind, cause(kind), run, {"rng": f"{seed}:{cls}:{i}"}))
    return cases



def write_problem(sb, doc: dict, name="problem.json") -> Path:
    f = sb.cwd / name
    f.write_text(json.dumps(doc, indent=1))
    return f


def objectives_of(out: Path):
    doc = A.result_of(out) or {}
    best = doc.get("best")
    return best.get("objectives") if isinstance(best, dict) else None


def same_objectives(a: dict, b: dict, rel=1e-9) -> bool:
    if not isinstance(a, dict) or not isinstance(b, dict) or set(a) != set(b):
        return False
    for k in a:
        x, y = a[k], b[k]
        if not isinstance(x, (int, float)) or not isinstance(y, (int, float)):
            return False
        if abs(x - y) > rel * max(1.0, abs(x), abs(y)):
            return False
    return True


def reference(ctx, key: str, make):
    """A reference computed once per campaign in its own sandbox (ctx.once)."""
    def wrapped():
        root = ctx.work / "refs" / key
        shutil.rmtree(root, ignore_errors=True)
        return make(A.Sandbox(root))
    return ctx.once(key, wrapped)


def run_checked(ctx, sb, prob: Path, out: Path, expect: str, checks: list, extra=()):
    """`hapsyn run` of prob into out, single-threaded: its outcome and the output directory's
    consistency appended to checks. Returns the run."""
    r = A.run(ctx, sb, ["run", str(prob), "--threads", "1", "--out", str(out), "--quiet"] + list(extra))
    c, d = A.classify(r, "accept" if expect == "same" else expect)
    checks.append((c, ("run: " + d) if d else ""))
    if r.rc is not None and r.rc >= 0 and not r.timed_out:
        probs = A.out_dir_problems(out, True)
        if probs:
            checks.append(("mixed", "; ".join(probs)))
    return r


def validate_and_run(ctx, sb, prob: Path, expect: str, mode: str, extra=()):
    """Runs `hapsyn validate` and (mode "both") `hapsyn run --threads 1 --out out`: the checks and
    the last Res. expect: refuse / accept / any."""
    checks = []
    r = A.run(ctx, sb, ["validate", str(prob)] + list(extra))
    c, d = A.classify(r, "accept" if expect == "same" else expect)
    checks.append((c, ("validate: " + d) if d else ""))
    out = sb.cwd / "out"
    if mode == "both" and not r.timed_out and (r.rc is None or r.rc >= 0):
        r = run_checked(ctx, sb, prob, out, expect, checks, extra)
        if r.rc is not None and r.rc >= 0 and not r.timed_out:
            if r.rc == 0 and A.result_of(out) is None:
                checks.append(("wrong", "exit 0 without a readable result.json"))
    return checks, r, out


def names_file(r, name: str) -> tuple:
    """A refusal of a file's content must name the file (the motion and point_list READMEs: errors
    name the file and line); one that does not points at a value computed from it (a NaN)."""
    line = A.first_error_line(r.err)
    if name in r.err:
        return "ok", line
    return "internal", "the refusal does not name the file " + name + ": " + line


def start_cmd(ctx, sb, argv: list, env_extra=None):
    """Like attack.start, for any program (the python class), under the same address-space limit."""
    env = dict(ctx.env)
    env.update(env_extra or {})
    full = list(argv)
    if ctx.prlimit and ctx.args.mem_mb > 0:
        full = [ctx.prlimit, f"--as={ctx.args.mem_mb * 1024 * 1024}", "--"] + full
    p = subprocess.Popen(full, cwd=str(sb.cwd), env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, start_new_session=True)
    return p, A.shline(full, env_extra, sb.cwd), argv


# ------------------------------------------------------------------------------------------------
# Class urdf: mutated URDF files of a small serial_chain study (the phantom 3R over a 27-point box,
# evaluate solver, gii and gdi: a run takes ~0.1 s).

URDF_MOVING = ["yaw_joint", "shoulder_joint", "elbow_joint"]
URDF_PATH_JOINTS = ["world_joint", "yaw_joint", "shoulder_joint", "elbow_joint", "gimbal_center_joint"]
URDF_PATH_LINKS = ["world", "base_link", "turret", "upper_arm", "forearm", "stylus_tip"]
URDF_BODY_LINKS = ["turret", "upper_arm", "forearm", "stylus_tip"]  # inertials on moving bodies
BAD = "\ue000"  # placeholder for an invalid UTF-8 byte (replaced by 0xff when the file is written)


def urdf_problem(urdf: Path, opts: dict) -> dict:
    o = {"urdf": str(urdf), "base_link": "world", "tip_link": "stylus_tip", "task": "position"}
    o.update(opts)
    return {"name": "attack-urdf", "mechanism": {"plugin": "serial_chain", "options": o},
            "scene": {"plugin": "box", "options": {"dimension": 3, "center": [0.18, 0.0, 0.0],
                                                   "size": [0.04, 0.04, 0.04], "step": 0.02}},
            "design": {}, "objectives": [{"metric": "gii", "sense": "maximize"}, {"metric": "gdi", "sense": "maximize"}],
            "solver": {"plugin": "evaluate"}, "seed": 1}


def block(t: str, tag: str, name: str):
    if tag == "joint":
        m = re.search(r'<joint name="%s".*?</joint>' % re.escape(name), t, re.S)
    else:
        m = re.search(r'<link name="%s"(?:\s*/>|>.*?</link>)' % re.escape(name), t, re.S)
    assert m, (tag, name)
    return m.start(), m.end()


def sub_block(t: str, tag: str, name: str, pattern: str, repl, count=1) -> str:
    s, e = block(t, tag, name)
    new, n = re.subn(pattern, repl, t[s:e], count=count, flags=re.S)
    assert n, (tag, name, pattern)
    return t[:s] + new + t[e:]


def rename(t: str, old: str, new: str) -> str:
    return re.sub(r'(name|link)="%s"' % re.escape(old), lambda m: f'{m.group(1)}="{new}"', t)


def inside_robot(t: str, what: str) -> str:
    i = t.index("</robot>")
    return t[:i] + what + "\n" + t[i:]


def billion_laughs(levels=9) -> str:
    ents = ['<!ENTITY l0 "lol">'] + [f'<!ENTITY l{i} "' + f"&l{i - 1};" * 10 + '">' for i in range(1, levels + 1)]
    return "<!DOCTYPE robot [\n" + "\n".join(ents) + "\n]>\n"


def urdf_mutate(rng: random.Random, kind: str, t: str):
    """(text, what, expect, option overrides, mode); expect: same (the control's objectives),
    refuse, any; mode: both (validate and run) or validate."""
    opts, mode = {}, "both"
    if kind == "control":
        return t, "the pristine file", "same", opts, mode
    if kind in ("axis-huge", "axis-tiny", "axis-scale"):
        j = rng.choice(URDF_MOVING)
        f = {"axis-huge": "1e200", "axis-tiny": "1e-200"}.get(kind) or rng.choice(["1e200", "1e-200", "7", "1e-150", "1e150"])
        t = sub_block(t, "joint", j, r'<axis xyz="([^"]*)"',
                      lambda m: '<axis xyz="' + " ".join(f if v == "1" else v for v in m.group(1).split()) + '"')
        return t, f"{j} axis scaled by {f}", "same", opts, mode
    if kind == "axis-zero":
        j = rng.choice(URDF_MOVING)
        return sub_block(t, "joint", j, r'<axis xyz="[^"]*"', '<axis xyz="0 0 0"'), f"{j} axis 0 0 0", "refuse", opts, mode
    if kind == "axis-bad":
        j = rng.choice(URDF_MOVING)
        v = rng.choice(["nan", "inf", "-inf", "abc", "1e400", "0 1", "", "1 0 0 0"])
        new = v if v in ("0 1", "", "1 0 0 0") else f"0 {v} 0"
        return sub_block(t, "joint", j, r'<axis xyz="[^"]*"', f'<axis xyz="{new}"'), f"{j} axis xyz={new!r}", "refuse", opts, mode
    if kind == "origin-bad":
        j = rng.choice(URDF_PATH_JOINTS)
        attr = rng.choice(["xyz", "rpy"])
        v = rng.choice(["nan", "inf", "abc", "1e400", "-nan", "0,1"])
        t = sub_block(t, "joint", j, r'<origin xyz="([^"]*)" rpy="([^"]*)"',
                      lambda m: f'<origin xyz="{m.group(1) if attr == "rpy" else "0 " + v + " 0"}" '
                                f'rpy="{m.group(2) if attr == "xyz" else "0 " + v + " 0"}"')
        return t, f"{j} origin {attr} = '0 {v} 0'", "refuse", opts, mode
    if kind == "joint-missing":
        j = rng.choice(URDF_PATH_JOINTS)
        s, e = block(t, "joint", j)
        return t[:s] + t[e:], f"joint {j} removed", "refuse", opts, mode
    if kind == "link-missing":
        ln = rng.choice(URDF_PATH_LINKS)
        s, e = block(t, "link", ln)
        return t[:s] + t[e:], f"link {ln} removed", "refuse", opts, mode
    if kind in ("joint-duplicate", "link-duplicate"):
        tag = kind.split("-")[0]
        name = rng.choice(URDF_PATH_JOINTS if tag == "joint" else URDF_PATH_LINKS)
        s, e = block(t, tag, name)
        return t[:e] + "\n  " + t[s:e] + t[e:], f"{tag} {name} twice", "refuse", opts, mode
    if kind == "loop":
        child = rng.choice(URDF_PATH_LINKS[1:])
        parent = rng.choice([ln for ln in URDF_PATH_LINKS + ["stylus", "gimbal_1"] if ln != child])
        j = (f'<joint name="loop_joint" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
             f'<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')
        return inside_robot(t, j), f"link {child} also the child of loop_joint (parent {parent})", "refuse", opts, mode
    if kind == "mass-bad":
        ln = rng.choice(URDF_BODY_LINKS)
        v = rng.choice(["-0.5", "nan", "inf", "-inf", "abc", "-1e-300", "0"])
        t = sub_block(t, "link", ln, r'<mass value="[^"]*"', f'<mass value="{v}"')
        return t, f"link {ln} mass {v}", ("any" if v == "0" else "refuse"), opts, mode
    if kind == "inertia-negative":
        ln = rng.choice(URDF_BODY_LINKS)
        c = rng.choice(["ixx", "iyy", "izz"])
        t = sub_block(t, "link", ln, c + r'="[^"]*"', c + '="-0.001"')
        return t, f"link {ln} {c} = -0.001", "refuse", opts, mode
    if kind == "inertia-triangle":
        ln = rng.choice(URDF_BODY_LINKS)
        s, e = block(t, "link", ln)
        vals = {k: float(v) for k, v in re.findall(r'(i[xyz]{2})="([^"]*)"', t[s:e])}
        c = rng.choice(["ixx", "iyy", "izz"])
        others = [vals[k] for k in ("ixx", "iyy", "izz") if k != c]
        v = 10 * sum(others) + 1e-3
        t = sub_block(t, "link", ln, c + r'="[^"]*"', f'{c}="{v:.6g}"')
        return t, f"link {ln} {c} = {v:.6g} > the sum of the other two (triangle inequality)", "refuse", opts, mode
    if kind == "limits-reversed":
        j = rng.choice(URDF_MOVING)
        t = sub_block(t, "joint", j, r'lower="([^"]*)" upper="([^"]*)"', lambda m: f'lower="{m.group(2)}" upper="{m.group(1)}"')
        return t, f"{j} limits lower > upper", "refuse", opts, mode
    if kind in ("deep-xml-1000", "deep-xml-100000", "deep-xml", "deep-xml-unclosed"):
        depth = {"deep-xml-1000": 1000, "deep-xml-100000": 100000}.get(kind) or rng.choice([1000, 10000, 100000, 300000])
        closed = kind != "deep-xml-unclosed"
        x = "<foo>" * depth + ("</foo>" * depth if closed else "")
        return (inside_robot(t, x), f"{depth} levels of <foo> inside <robot>" + ("" if closed else ", unclosed"),
                "refuse", opts, "validate" if depth > 10000 else mode)
    if kind in ("fixed-300k", "fixed-chain"):
        n = 300000 if kind == "fixed-300k" else rng.choice([100, 1000, 20000])
        parts, prev = [], "stylus_tip"
        for i in range(n):
            parts.append(f'<link name="f{i}"/><joint name="fj{i}" type="fixed"><parent link="{prev}"/>'
                         f'<child link="f{i}"/></joint>\n')
            prev = f"f{i}"
        opts["tip_link"] = prev
        return (inside_robot(t, "".join(parts)), f"{n} fixed joints in a chain after stylus_tip (tip_link {prev})", "any",
                opts, "validate" if n > 1000 else mode)
    if kind == "long-name":
        n = rng.choice([1000, 100000, 1000000])
        old = rng.choice(URDF_PATH_JOINTS + ["turret", "upper_arm", "forearm"])
        return rename(t, old, "n" * n), f"{old} renamed to a name of {n} characters", "any", opts, mode
    if kind == "badutf8-name":
        old = rng.choice(URDF_PATH_JOINTS + ["base_link", "turret", "upper_arm", "forearm"])
        return rename(t, old, old[:3] + BAD + old[3:]), f"invalid UTF-8 (0xff) in the name {old}", "refuse", opts, mode
    if kind == "truncate":
        n = rng.randrange(10, t.index("</robot>"))
        return t[:n], f"truncated at character {n} of {len(t)}", "refuse", opts, mode
    if kind == "entities":
        v = rng.choice(["laughs", "amp", "undefined", "charref"])
        if v == "laughs":
            t = t.replace('<?xml version="1.0"?>', '<?xml version="1.0"?>\n' + billion_laughs())
            t = t.replace('<robot name="phantom_3r">', '<robot name="&l9;">')
            return t, "billion laughs: an entity expanding to 10^9 'lol' as the robot's name", "any", opts, mode
        if v == "amp":
            return rename(t, "upper_arm", "upper&amp;arm"), "'&amp;' in a link name", "any", opts, mode
        if v == "undefined":
            return t.replace('name="turret"', 'name="tur&bogus;ret"'), "an undefined entity in a link name", "any", opts, mode
        return rename(t, "forearm", "fore&#65;rm"), "a character reference in a link name", "any", opts, mode
    if kind == "doctype":
        d = rng.choice(['<!DOCTYPE robot SYSTEM "/dev/zero">', '<!DOCTYPE robot SYSTEM "http://127.0.0.1:9/x.dtd">',
                        '<!DOCTYPE robot [<!ELEMENT robot ANY>]>'])
        return t.replace('<?xml version="1.0"?>', '<?xml version="1.0"?>\n' + d), f"a DOCTYPE: {d}", "any", opts, mode
    if kind == "two-roots":
        return (t + '<robot name="second"><link name="a"/></robot>\n', "a second <robot> after the first", "refuse",
                opts, mode)
    if kind == "comments-cdata":
        t = t.replace("<link name=\"turret\">", "<!-- a <joint name=\"x\"/> comment -->\n<link name=\"turret\">"
                      "<![CDATA[ <joint name=\"elbow_joint\"> ]]>")
        t = inside_robot(t, "<!-- -- -->" if rng.random() < 0.3 else "<![CDATA[ ]]> <!-- end -->")
        what = "comments and CDATA between and inside elements"
        return t, what, ("any" if "-- --" in t else "same"), opts, mode
    if kind == "huge-attr":
        v = rng.choice(["robot-name", "link-attr", "origin-digits", "mass-digits"])
        big = 3 * 1024 * 1024
        if v == "robot-name":
            t = t.replace('<robot name="phantom_3r">', '<robot name="' + "R" * big + '">')
            return t, "a 3 MB robot name", "same", opts, mode
        if v == "link-attr":
            t = t.replace('<link name="upper_arm">', '<link name="upper_arm" note="' + "x" * big + '">')
            return t, "a 3 MB unknown attribute on link upper_arm", "same", opts, mode
        if v == "origin-digits":
            t = sub_block(t, "joint", "elbow_joint", r'<origin xyz="[^"]*"', '<origin xyz="0.215' + "0" * big + ' 0 0"')
            return t, "elbow_joint origin x = 0.215 followed by 3 MB of zeros", "any", opts, mode
        t = sub_block(t, "link", "forearm", r'<mass value="[^"]*"', '<mass value="' + "9" * big + '"')
        return t, "forearm mass: 3 MB of nines", "refuse", opts, mode
    if kind == "base-tip":
        v = rng.choice(["base-missing", "tip-missing", "reversed", "same", "tip-branch", "empty"])
        opts.update({"base-missing": {"base_link": "no_such_link"}, "tip-missing": {"tip_link": "no_such_link"},
                     "reversed": {"base_link": "stylus_tip", "tip_link": "world"},
                     "same": {"base_link": "forearm", "tip_link": "forearm"},
                     "tip-branch": {"tip_link": "stylus"}, "empty": {"base_link": ""}}[v])
        return t, f"base_link/tip_link {v}: {json.dumps(opts)}", ("any" if v == "tip-branch" else "refuse"), opts, mode
    if kind == "bom-crlf":
        return "\ufeff" + t.replace("\n", "\r\n"), "byte-order mark and CRLF line ends", "any", opts, mode
    raise ValueError(kind)


URDF_FIXED = ["axis-huge", "axis-zero", "deep-xml-1000", "fixed-300k", "inertia-triangle", "badutf8-name", "axis-tiny",
              "deep-xml-100000", "control", "mass-bad", "inertia-negative", "loop", "base-tip", "truncate", "huge-attr",
              "entities", "doctype", "comments-cdata", "joint-duplicate", "link-missing", "limits-reversed", "origin-bad",
              "joint-missing", "long-name", "link-duplicate", "axis-bad", "deep-xml-unclosed", "bom-crlf", "two-roots"]
URDF_RANDOM = [k for k in URDF_FIXED if k not in ("control", "deep-xml-1000", "deep-xml-100000", "fixed-300k",
                                                  "axis-huge", "axis-tiny")] + ["axis-scale", "deep-xml", "fixed-chain"]
URDF_CAUSE = {"deep-xml-1000": "urdf: deep XML nesting (stack overflow)", "deep-xml-100000": "urdf: deep XML nesting (stack overflow)",
              "deep-xml": "urdf: deep XML nesting (stack overflow)", "deep-xml-unclosed": "urdf: deep XML nesting (stack overflow)",
              "fixed-300k": "urdf: long chains of fixed joints (stack overflow)",
              "fixed-chain": "urdf: long chains of fixed joints (stack overflow)",
              "axis-huge": "urdf: axis not normalised robustly", "axis-tiny": "urdf: axis not normalised robustly",
              "axis-scale": "urdf: axis not normalised robustly"}


def urdf_control(ctx) -> dict:
    def make(sb):
        u = sb.cwd / "robot.urdf"
        shutil.copy(PHANTOM_URDF, u)
        prob = write_problem(sb, urdf_problem(u, {}))
        r = A.run(ctx, sb, ["run", str(prob), "--threads", "1", "--out", str(sb.cwd / "out"), "--quiet"], timeout=120)
        objs = objectives_of(sb.cwd / "out")
        if r.rc != 0 or not objs:
            raise RuntimeError(f"the unmutated URDF study failed ({r.rc}): {A.tail(r.err)}")
        return objs
    return reference(ctx, "urdf-control", make)


def case_urdf(ctx, case, sb):
    rng = random.Random(case.params["rng"])
    text, what, expect, opts, mode = urdf_mutate(rng, case.kind, PHANTOM_URDF.read_text())
    u = sb.cwd / "robot.urdf"
    u.write_bytes(text.encode("utf-8").replace(BAD.encode("utf-8"), b"\xff"))
    prob = write_problem(sb, urdf_problem(u, opts))
    control = urdf_control(ctx) if expect == "same" else None
    checks, r, out = validate_and_run(ctx, sb, prob, "accept" if expect == "same" else expect, mode)
    if expect == "same" and r.rc == 0 and mode == "both":
        got = objectives_of(out)
        if not same_objectives(got, control):
            checks.append(("wrong", f"objectives {got} differ from the unmutated file's {control}"))
    cat, det = A.worst(*checks)
    return A.outcome(r, cat, what + (": " + det if det else ""))


def gen_urdf(seed: int, n: int) -> list:
    return generated("urdf", seed, n, URDF_FIXED, URDF_RANDOM, case_urdf, lambda k: URDF_CAUSE.get(k, f"urdf: {k}"))


# ------------------------------------------------------------------------------------------------
# Class dh: mutated DH tables (hapsyn-dh JSON) of a serial_chain study (the haptic 6R, position
# task over an 8-point box, evaluate solver).

def dh_problem(f: Path) -> dict:
    return {"name": "attack-dh",
            "mechanism": {"plugin": "serial_chain", "options": {"dh_file": str(f), "task": "position"}},
            "scene": {"plugin": "box", "options": {"dimension": 3, "center": [0.5, 0.3, -0.3],
                                                   "size": [0.04, 0.04, 0.04], "step": 0.04}},
            "design": {}, "objectives": [{"metric": "gii", "sense": "maximize"}, {"metric": "gdi", "sense": "maximize"}],
            "solver": {"plugin": "evaluate"}, "seed": 1}


DH_REQUIRED = [("format",), ("format_version",), ("convention",), ("units",), ("units", "length"), ("units", "angle"),
               ("joints",), ("joints", 0, "joint"), ("joints", 2, "theta"), ("joints", 3, "alpha"), ("joints", 1, "a"),
               ("joints", 4, "d"), ("mass_model", "motor_mass")]


def dh_mutate(rng: random.Random, kind: str, text: bytes):
    doc = json.loads(text)
    paths = [p for p in A.all_paths(doc) if p]
    numbers = [p for p in paths if isinstance(A.get_at(doc, p), (int, float)) and not isinstance(A.get_at(doc, p), bool)]
    strings = [p for p in paths if isinstance(A.get_at(doc, p), str)]
    containers = [p for p in paths if isinstance(A.get_at(doc, p), (dict, list))]
    pt = A.set_path_text
    if kind == "control":
        return text, "the pristine file", "accept"
    if kind in ("deep-10000", "deep-200000", "deep"):
        depth = {"deep-10000": 10000, "deep-200000": 200000}.get(kind) or rng.choice([1000, 10000, 100000, 200000])
        shape = rng.choice(["array", "object"])
        p = rng.choice(paths)
        doc = A.set_at(doc, p, A.Raw(A.deep(depth, shape)))
        return A.jdump(doc), f"{pt(p)} = {shape}s nested {depth} deep", "refuse"
    if kind == "nan":
        p = rng.choice(numbers)
        v = rng.choice([b"NaN", b"Infinity", b"-Infinity", b"nan"])
        return A.jdump(A.set_at(doc, p, A.Raw(v))), f"{pt(p)} = {v.decode()}", "refuse"
    if kind == "hugenum":
        p = rng.choice(numbers)
        v = rng.choice(["1e400", "-1e400", "1e308", "-1e308", "1e-320", "18446744073709551616", "1" + "0" * 400])
        exp = "refuse" if v in ("1e400", "-1e400", "1" + "0" * 400) else "any"
        return A.jdump(A.set_at(doc, p, A.Raw(v.encode()))), f"{pt(p)} = {v[:30]}", exp
    if kind == "wrongtype":
        p = ("joints", 2, "alpha") if rng.random() < 0.2 else rng.choice(paths)
        old = A.get_at(doc, p)
        pool = [v for v in [0, -1, 1.5, "", "x", "l1", True, None, [], {}, [1, 2], {"a": 1}] if type(v) is not type(old)]
        v = rng.choice(pool)
        return A.jdump(A.set_at(doc, p, v)), f"{pt(p)} = {json.dumps(v)} (was {type(old).__name__})", "any"
    if kind == "joints-empty":
        doc["joints"] = []
        return A.jdump(doc), "joints = []", "refuse"
    if kind == "empty":
        p = rng.choice(containers)
        v = rng.choice([{}, []])
        return A.jdump(A.set_at(doc, p, v)), f"{pt(p)} = {json.dumps(v)}", "any"
    if kind in ("missing", "missing-required"):
        if kind == "missing-required":
            p = rng.choice(DH_REQUIRED)
        else:
            p = rng.choice([q for q in paths if isinstance(q[-1], str)])
        del A.get_at(doc, p[:-1])[p[-1]]
        return A.jdump(doc), f"{pt(p)} removed", ("refuse" if kind == "missing-required" else "any")
    if kind == "badutf8":
        p = ("joints", rng.randrange(6), "joint") if rng.random() < 0.5 else rng.choice(strings)
        bad = rng.choice([b"\xff", b"\xc0\xaf", b"\xed\xa0\x80", b"\xe2\x82"])
        s = json.dumps(A.get_at(doc, p), ensure_ascii=False).encode()
        return A.jdump(A.set_at(doc, p, A.Raw(s[:-1] + bad + b'"'))), f"{pt(p)}: invalid UTF-8 {bad!r}", "refuse"
    if kind == "too-many-joints":
        doc["joints"] = doc["joints"] + [dict(doc["joints"][-1], joint=f"extra{i}") for i in range(rng.choice([2, 100]))]
        doc["mass_model"]["motor_mass"] = [1.0] * len(doc["joints"])
        return A.jdump(doc), f"{len(doc['joints'])} joints", "refuse"
    if kind == "named-length":
        i = rng.randrange(6)
        k = rng.choice(["a", "d"])
        v = rng.choice(["--l1", "l9", "-", "", "l1 ", "L1", "-l1-"])
        doc["joints"][i][k] = v
        return A.jdump(doc), f"joints[{i}].{k} = {json.dumps(v)}", "refuse"
    if kind == "negative-length":
        k = rng.choice(list(doc["parameters"]))
        doc["parameters"][k] = rng.choice([-0.1, -1e-300])
        return A.jdump(doc), f"parameters.{k} = {doc['parameters'][k]}", "refuse"
    if kind == "limits-reversed":
        i = rng.randrange(6)
        doc["joints"][i]["lower"], doc["joints"][i]["upper"] = 10, -10
        return A.jdump(doc), f"joints[{i}] lower 10 > upper -10", "refuse"
    if kind == "dupkey":
        obj_paths = [p for p in A.all_paths(doc) if isinstance(A.get_at(doc, p), dict) and A.get_at(doc, p)]
        p = rng.choice(obj_paths)
        obj = A.get_at(doc, p)
        k = rng.choice(list(obj))
        items = list(obj.items())
        items.insert(rng.randrange(len(items) + 1), (k, obj[k]))
        return A.jdump(A.set_at(doc, p, A.Pairs(items))), f"duplicate key {pt(p + (k,)) or k}", "refuse"
    if kind == "duplicate-joint-name":
        doc["joints"][3]["joint"] = doc["joints"][1]["joint"]
        return A.jdump(doc), "joints[3].joint = joints[1].joint", "refuse"
    raise ValueError(kind)


DH_FIXED = ["deep-10000", "deep-200000", "nan", "wrongtype", "badutf8", "joints-empty", "missing-required", "hugenum",
            "control", "too-many-joints", "named-length", "negative-length", "limits-reversed", "dupkey",
            "duplicate-joint-name", "empty", "missing"]
DH_RANDOM = ["deep", "nan", "hugenum", "wrongtype", "wrongtype", "wrongtype", "badutf8", "empty", "missing", "missing",
             "missing-required", "named-length", "dupkey", "limits-reversed"]


def case_dh(ctx, case, sb):
    rng = random.Random(case.params["rng"])
    data, what, expect = dh_mutate(rng, case.kind, DH_FILE.read_bytes())
    f = sb.cwd / "arm_dh.json"
    f.write_bytes(data)
    prob = write_problem(sb, dh_problem(f))
    deep = case.kind.startswith("deep")
    checks, r, out = validate_and_run(ctx, sb, prob, expect, "validate" if deep else "both")
    cat, det = A.worst(*checks)
    return A.outcome(r, cat, what + (": " + det if det else ""))


def gen_dh(seed: int, n: int) -> list:
    return generated("dh", seed, n, DH_FIXED, DH_RANDOM, case_dh,
                     lambda k: "dh: deep JSON nesting (stack overflow)" if k.startswith("deep") else f"dh: {k}")


# ------------------------------------------------------------------------------------------------
# Class csv: point_list scene CSVs (2-D, exported with `hapsyn scene --csv` and run as the scene of
# the five-bar Table 2 design) and motion-scene CSV recordings (exported).

PL_BASE = ["# A hostile-input base: the planar example's nine points.", "# units: length=mm", "x,y,weight",
           "-50,-50,1", "0,-50,2", "50,-50,1", "-50,0,2", "0,0,4", "50,0,2", "-50,50,1", "0,50,2", "50,50,1"]
MOTION_ROWS = 150


def motion_base() -> list:
    lines = MOTION_CSV.read_text().splitlines()
    head = [ln for ln in lines[:10] if ln.startswith("#")]
    i = len(head)
    return head + [lines[i]] + lines[i + 1:i + 1 + MOTION_ROWS]


def scene_doc(kind: str, f: Path) -> dict:
    if kind == "pl":
        return {"scene": {"plugin": "point_list", "options": {"file": str(f)}}}
    return {"scene": {"plugin": "motion", "options": {"path": str(f)}}}


def pl_run_doc(f: Path) -> dict:
    doc = json.loads((A.PROBLEMS / "fivebar-table2-best-gii.json").read_text())
    doc["scene"] = {"plugin": "point_list", "options": {"file": str(f)}}
    doc.pop("output", None)
    return doc


def data_rows(lines: list) -> list:
    """Indices of the data rows (after the header line)."""
    idx = [i for i, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith("#")]
    return idx[1:]


def csv_mutate(rng: random.Random, kind: str):
    """(file kind pl|mo, bytes, what, expect same|refuse|any|accept, extra)."""
    fk = kind.split("-")[0]
    lines = list(PL_BASE) if fk == "pl" else motion_base()
    rows = data_rows(lines)
    hdr = rows[0] - 1
    k = kind.split("-", 1)[1] if "-" in kind else kind
    enc = lambda ls, nl="\n": (nl.join(ls) + nl).encode()  # noqa: E731
    if k == "control":
        return fk, enc(lines), "the pristine file", "same"
    if k == "units-at-end":
        u = lines.index("# units: length=mm")
        ls = lines[:u] + lines[u + 1:] + ["# units: length=mm"]
        return fk, enc(ls), "the units line after the last row", "same"
    if k == "huge-rows":
        n = 2_000_000 if fk == "pl" else 200_000
        if fk == "pl":
            body = "".join(f"{i % 100 - 50},{(i // 100) % 100 - 50},1\n" for i in range(n))
            return fk, enc(lines[:hdr + 1]) + body.encode(), f"{n} rows", "any"
        base = [ln.split(",") for ln in lines[rows[0]:]]
        body = "".join(f"{i / 120.0:.6f}," + ",".join(base[i % len(base)][1:]) + "\n" for i in range(n))
        return fk, enc(lines[:hdr + 1]) + body.encode(), f"{n} rows at 120 Hz", "any"
    if k == "tiny-steps":
        base = [ln.split(",") for ln in lines[rows[0]:]]
        out = lines[:hdr + 1]
        while len("\n".join(out)) < 4096:
            j = len(out) - hdr - 1
            out.append(f"{j * 1e-9:.12g}," + ",".join(base[j % len(base)][1:]))
        return fk, enc(out), f"{len(out) - hdr - 1} rows 1e-9 s apart (4 kB)", "refuse"
    if k == "tiny-steps-gap":
        base = [ln.split(",") for ln in lines[rows[0]:]]
        out = lines[:hdr + 1] + [f"{j * 1e-9:.12g}," + ",".join(base[j][1:]) for j in range(len(base) - 1)]
        out.append("100," + ",".join(base[-1][1:]))
        return fk, enc(out), f"{len(base) - 1} rows 1e-9 s apart, then one at 100 s (1e11 samples at the median rate)", \
            "refuse"
    if k == "non-increasing":
        i = rng.randrange(2, len(rows) - 2)
        f = lines[rows[i]].split(",")
        g = lines[rows[i - 1]].split(",")
        f[0] = rng.choice([g[0], str(float(g[0]) - 0.5)])
        lines[rows[i]] = ",".join(f)
        return fk, enc(lines), f"row {i}: time {f[0]} after {g[0]}", "refuse"
    if k == "badutf8-column":
        if fk == "pl":
            lines[hdr] = "x,y,weight,stiff\udcffness"
            for i in rows:
                lines[i] += ",1"
        else:
            cols = lines[hdr].split(",")
            cols[-1] = cols[-1] + "\udcff"
            lines[hdr] = ",".join(cols)
        data = "\n".join(lines).encode("utf-8", "surrogateescape") + b"\n"
        return fk, data, "invalid UTF-8 in a column name", "refuse"
    if k == "bom":
        return fk, b"\xef\xbb\xbf" + enc(lines), "a byte-order mark", "same"
    if k == "crlf":
        return fk, enc(lines, "\r\n"), "CRLF line ends", "same"
    if k == "empty":
        return fk, b"", "an empty file", "refuse"
    if k == "header-only":
        return fk, enc(lines[:hdr + 1]), "the header without rows", "refuse"
    if k == "wrong-width":
        i = rng.choice(rows)
        f = lines[i].split(",")
        lines[i] = ",".join(f[:-1] if rng.random() < 0.5 else f + ["0"])
        return fk, enc(lines), f"line {i + 1} with {len(lines[i].split(','))} fields", "refuse"
    if k in ("non-number", "nan"):
        i = rng.choice(rows)
        f = lines[i].split(",")
        c = rng.randrange(len(f))
        f[c] = rng.choice(["abc", "1.2.3", "0x", "", "1e", "--1", "1,5"] if k == "non-number"
                          else ["nan", "inf", "-inf", "1e400", "NAN", "infinity"])
        lines[i] = ",".join(f)
        return fk, enc(lines), f"line {i + 1} field {c + 1} = {f[c]!r}", "refuse"
    if k == "units-twice":
        lines.append("# units: length=m")
        return fk, enc(lines), "a second units line at the end", "refuse"
    if k == "units-bad":
        u = lines.index("# units: length=mm")
        lines[u] = rng.choice(["# units: length=inch", "# units: angle=deg", "# units: length=", "# units: length=mm; x"])
        return fk, enc(lines), f"units line {lines[u]!r}", "refuse"
    if k == "units-spelling":
        u = lines.index("# units: length=mm")
        lines[u] = rng.choice(["# Units: length=mm", "# unit: mm", "# units : length=mm", "# UNITS: length=mm",
                               "# units: length=mm, length=cm"])
        return fk, enc(lines), f"units line {lines[u]!r} (another spelling, or the length twice)", "refuse"
    if k == "weights-overflow":
        ls = [ln.rsplit(",", 1)[0] + ",1e308" if i > hdr else ln for i, ln in enumerate(lines)]  # PL_BASE's weight column
        return fk, enc(ls), "finite weights whose sum overflows", "refuse"
    if k == "export-relative":
        return fk, enc(lines), "scene --csv into a bare relative file name", "accept"
    if k == "header-key":
        lines.insert(1, rng.choice(["# unit: inch", "# time_unit: h", "# bogus: 1", "# subject: " + "S" * 100000]))
        return fk, enc(lines), f"header line {lines[1][:40]!r}", "any"
    if k == "quaternion":
        i = rng.choice(rows)
        f = lines[i].split(",")
        f[4:8] = rng.choice([["0", "0", "0", "0"], ["2", "0", "0", "0"], ["1e200", "1e200", "0", "0"]])
        lines[i] = ",".join(f)
        return fk, enc(lines), f"line {i + 1}: quaternion {f[4:8]}", "refuse"
    raise ValueError(kind)


CSV_FIXED = ["pl-units-at-end", "pl-huge-rows", "mo-tiny-steps", "mo-non-increasing", "pl-badutf8-column", "pl-bom",
             "mo-crlf", "pl-empty", "mo-tiny-steps-gap", "pl-header-only", "mo-badutf8-column", "pl-wrong-width",
             "pl-nan", "mo-header-only", "pl-crlf", "pl-export-relative", "mo-bom", "mo-wrong-width",
             "mo-non-number", "pl-non-number", "pl-units-twice", "mo-huge-rows", "mo-empty", "mo-quaternion",
             "pl-units-bad", "mo-header-key", "mo-control", "pl-units-spelling", "pl-weights-overflow"]
CSV_RANDOM = ["pl-wrong-width", "pl-non-number", "pl-nan", "mo-wrong-width", "mo-non-number", "mo-nan",
              "mo-non-increasing", "mo-quaternion", "mo-header-key", "pl-units-bad", "pl-units-twice",
              "pl-units-spelling", "pl-weights-overflow"]


def csv_control(ctx, fk: str) -> bytes:
    def make(sb):
        f = sb.cwd / ("points.csv" if fk == "pl" else "rec.csv")
        f.write_bytes(("\n".join(PL_BASE if fk == "pl" else motion_base()) + "\n").encode())
        s = write_problem(sb, scene_doc(fk, f), "scene.json")
        r = A.run(ctx, sb, ["scene", str(s), "--csv", str(sb.cwd / "export.csv")], timeout=120)
        if r.rc != 0:
            raise RuntimeError(f"the pristine {fk} scene failed ({r.rc}): {A.tail(r.err)}")
        return (sb.cwd / "export.csv").read_bytes()
    return reference(ctx, f"csv-control-{fk}", make)


def case_csv(ctx, case, sb):
    rng = random.Random(case.params["rng"])
    fk, data, what, expect = csv_mutate(rng, case.kind)
    f = sb.cwd / ("points.csv" if fk == "pl" else "rec.csv")
    f.write_bytes(data)
    s = write_problem(sb, scene_doc(fk, f), "scene.json")
    huge = "huge" in case.kind
    export = sb.cwd / "export.csv"
    argv = ["scene", str(s)]
    if not huge:
        argv += ["--csv", "export.csv" if case.kind.endswith("export-relative") else str(export)]
    r = r_scene = A.run(ctx, sb, argv)
    c, d = A.classify(r, "accept" if expect == "same" else expect)
    checks = [(c, ("scene: " + d) if d else "")]
    if r.rc == 1 and c == "ok" and not case.kind.endswith("export-relative"):
        checks.append(names_file(r, f.name))
    if expect == "same" and r.rc == 0:
        ref = csv_control(ctx, fk)
        got = export.read_bytes() if export.exists() else None
        if got != ref:
            checks.append(("wrong", "the exported scene differs from the pristine file's" +
                           (" (no export written)" if got is None else "")))
    if fk == "pl" and not huge and not r.timed_out and (r.rc is None or r.rc >= 0):
        prob = write_problem(sb, pl_run_doc(f))
        out = sb.cwd / "out"
        run_checked(ctx, sb, prob, out, expect, checks)
    cat, det = A.worst(*checks)
    if checks[0][0] != "ok" or (len(checks) > 1 and checks[1][0] != "ok" and checks[1][1].startswith("the ")):
        r = r_scene  # the failure is the scene step's: show its command
    return A.outcome(r, cat, what + (": " + det if det else ""))


def gen_csv(seed: int, n: int) -> list:
    return generated("csv", seed, n, CSV_FIXED, CSV_RANDOM, case_csv,
                     lambda k: ("point_list" if k.startswith("pl") else "motion") + ": " + k.split("-", 1)[1])


# ------------------------------------------------------------------------------------------------
# Class bvh: BVH recordings of the motion scene (the synthetic S01/drinking.bvh cut to 120 frames),
# exported with `hapsyn scene --csv`.

BVH_FRAMES = 120


def bvh_base() -> tuple:
    text = MOTION_BVH.read_text()
    head, motion = text.split("MOTION\n", 1)
    ml = motion.splitlines()
    frames = ml[2:2 + BVH_FRAMES]
    return head, ml[1], frames  # hierarchy, "Frame Time: ..." line, frame lines


def bvh_text(head, frames, count=None, ftime="Frame Time: 0.00833333333") -> str:
    return head + "MOTION\n" + f"Frames: {len(frames) if count is None else count}\n" + ftime + "\n" + "\n".join(frames) + "\n"


def deep_joints(depth: int, channels: bool) -> str:
    ch = "CHANNELS 0\n" if channels else ""
    return ("".join(f"JOINT D{i}\n{{\nOFFSET 0 0 0\n{ch}" for i in range(depth)) + "End Site\n{\nOFFSET 0 0 0\n}\n"
            + "}\n" * depth)


def bvh_mutate(rng: random.Random, kind: str):
    head, ft, frames = bvh_base()
    if kind == "control":
        return bvh_text(head, frames, ftime=ft), "the pristine file (120 frames)", "accept"
    if kind == "truncated-hierarchy":
        n = rng.randrange(5, len(head) - 2)
        return head[:n], f"cut inside the hierarchy at character {n}", "refuse"
    if kind == "channels-mismatch":
        i = rng.randrange(len(frames))
        f = frames[i].split()
        frames[i] = " ".join(f[:-rng.randint(1, 3)] if rng.random() < 0.5 else f + ["0"] * rng.randint(1, 3))
        return bvh_text(head, frames, ftime=ft), f"frame {i}: {len(frames[i].split())} values for {len(f)} channels", "refuse"
    if kind in ("frame-time-0", "frame-time-negative", "frame-time-tiny", "frame-time-bad"):
        v = {"frame-time-0": "0", "frame-time-negative": "-0.0083", "frame-time-tiny": "1e-12"}.get(kind) or \
            rng.choice(["nan", "inf", "abc", "1e400", "", "1e300"])
        return bvh_text(head, frames, ftime=f"Frame Time: {v}"), f"Frame Time: {v}", "refuse"
    if kind in ("deep-joints-1000", "deep-joints-100000", "deep-joints"):
        depth = {"deep-joints-1000": 1000, "deep-joints-100000": 100000}.get(kind) or rng.choice([100, 1000, 10000, 100000])
        i = head.index("    JOINT RightShoulder")
        h = head[:i] + deep_joints(depth, True) + head[i:]
        return bvh_text(h, frames, ftime=ft), f"{depth} nested JOINT blocks (CHANNELS 0) beside RightShoulder", "any"
    if kind == "missing-hand":
        new = rng.choice(["LeftHand", "RightHandX", "righthand"])
        return bvh_text(head.replace("JOINT RightHand", "JOINT " + new), frames, ftime=ft), \
            f"no joint RightHand (renamed {new})", "refuse"
    if kind == "missing-shoulder":
        return bvh_text(head.replace("JOINT RightArm", "JOINT RightArmX"), frames, ftime=ft), "no joint RightArm", "refuse"
    if kind == "huge-frames":
        v = rng.choice(["2000000000", "9223372036854775807", "18446744073709551615", "99999999999999999999"]) \
            if rng.random() < 0.7 else "2000000000"
        return bvh_text(head, frames, count=v, ftime=ft), f"Frames: {v} declared, {len(frames)} given", "refuse"
    if kind == "frames-count":
        v = rng.choice(["-1", "0", str(BVH_FRAMES + 1), str(BVH_FRAMES * 10), "1.5", "abc", ""])
        return bvh_text(head, frames, count=v, ftime=ft), f"Frames: {v!r} declared, {len(frames)} given", "refuse"
    if kind in ("non-number", "nan"):
        i = rng.randrange(len(frames))
        f = frames[i].split()
        c = rng.randrange(len(f))
        f[c] = rng.choice(["abc", "1.2.3", "--1", "1e", "0x1p3"] if kind == "non-number" else ["nan", "inf", "-inf", "1e400"])
        frames[i] = " ".join(f)
        return bvh_text(head, frames, ftime=ft), f"frame {i} channel {c} = {f[c]!r}", "refuse"
    if kind == "channels-decl":
        v = rng.choice(["CHANNELS 99 Zrotation Xrotation Yrotation", "CHANNELS 3 Zrotation Xrotation Wrotation",
                        "CHANNELS -3 Zrotation Xrotation Yrotation", "CHANNELS 4294967299 Zrotation Xrotation Yrotation",
                        "CHANNELS 3 Zrotation Xrotation"])
        h = head.replace("CHANNELS 3 Zrotation Xrotation Yrotation", v, 1)
        return bvh_text(h, frames, ftime=ft), f"the first 3-channel declaration is {v!r}", "refuse"
    if kind == "offset-bad":
        v = rng.choice(["nan 0 0", "1e400 0 0", "0 0", "a b c", "inf inf inf"])
        h = head.replace("OFFSET -16.302899 0 0", "OFFSET " + v)
        return bvh_text(h, frames, ftime=ft), f"RightArm OFFSET {v}", "refuse"
    if kind == "no-motion":
        return head, "no MOTION section", "refuse"
    if kind == "empty":
        return "", "an empty file", "refuse"
    if kind == "short":
        n = rng.choice([0, 1, 5, 15])
        return bvh_text(head, frames[:n], ftime=ft), f"{n} frames", "refuse"
    if kind == "braces":
        v = rng.choice(["unbalanced-open", "unbalanced-close", "missing-root"])
        if v == "unbalanced-open":
            h = head.replace("  JOINT Spine\n  {", "  JOINT Spine\n  {\n  {")
        elif v == "unbalanced-close":
            h = head.replace("  JOINT Spine\n  {", "  JOINT Spine\n  }")
        else:
            h = head.replace("ROOT Hips", "Hips")
        return bvh_text(h, frames, ftime=ft), f"hierarchy {v}", "refuse"
    raise ValueError(kind)


BVH_FIXED = ["truncated-hierarchy", "channels-mismatch", "frame-time-0", "frame-time-negative", "frame-time-tiny",
             "deep-joints-1000", "missing-hand", "huge-frames", "deep-joints-100000", "control", "non-number", "nan",
             "frames-count", "channels-decl", "offset-bad", "no-motion", "empty", "short", "missing-shoulder", "braces",
             "frame-time-bad"]
BVH_RANDOM = ["truncated-hierarchy", "channels-mismatch", "frame-time-bad", "deep-joints", "missing-hand", "huge-frames",
              "frames-count", "non-number", "nan", "channels-decl", "offset-bad", "short", "braces"]


def case_bvh(ctx, case, sb):
    rng = random.Random(case.params["rng"])
    text, what, expect = bvh_mutate(rng, case.kind)
    f = sb.cwd / "rec.bvh"
    f.write_bytes(text.encode())
    s = write_problem(sb, scene_doc("mo", f), "scene.json")
    r = A.run(ctx, sb, ["scene", str(s), "--csv", str(sb.cwd / "export.csv")])
    checks = [A.classify(r, expect)]
    if r.rc == 1 and checks[0][0] == "ok":
        checks.append(names_file(r, f.name))
    cat, det = A.worst(*checks)
    return A.outcome(r, cat, what + (": " + det if det else ""))


def gen_bvh(seed: int, n: int) -> list:
    return generated("bvh", seed, n, BVH_FIXED, BVH_RANDOM, case_bvh, lambda k: f"bvh: {k}")


# ------------------------------------------------------------------------------------------------
# Class python: misuse of the Python module, each in its own interpreter under the timeout.

PY_METRIC = "py_attack_metric"
PY_SCRIPT = r'''
import json, sys, traceback
report = {"kind": "ok"}
try:
    import numpy as np
    try:
        import hapsyn
    except ImportError as e:
        print("ATTACK-REPORT " + json.dumps({"kind": "import-error", "message": str(e)}), flush=True)
        sys.exit(0)
    MODE, WHERE, CALL = sys.argv[1], sys.argv[2], sys.argv[3]
    prob = json.load(open(sys.argv[4]))
    prob["objectives"] = [{"metric": "%(name)s"}]
    S = {}

    def act(where, n):
        if MODE == "reenter-evaluate": S["study"].evaluate([])
        if MODE == "reenter-run": S["study"].run(threads=1)
        if MODE == "load-inside" and not S.get("inside"):  # once: the inner study's metric must not recurse
            S["inside"] = True
            hapsyn.load(prob, metrics={"%(name)s": Metric}).evaluate([])
        if MODE == "raise": raise KeyError("raised inside the metric")
        if MODE == "keyboard": raise KeyboardInterrupt()
        if MODE == "systemexit": raise SystemExit(7)
        v = {"str": "abc", "none": None, "list-long": [1.0] * (n + 1), "list-short": [1.0] * max(0, n - 1),
             "shape": np.zeros((n, 3)), "shape3d": np.zeros((n, 1, 1)), "strarr": np.array(["a"] * n),
             "objarr": np.array([object()] * n, dtype=object),
             "nan": np.full((n, 1), np.nan) if where == "local" else float("nan"),
             "complex": np.zeros((n, 1), dtype=complex) if where == "local" else complex(1, 1),
             "dict": {"a": 1}, "bool": True, "int": 3,
             "tuple": (1.0, 2.0), "array2": np.array([0.5, 0.5]), "inf": float("inf"), "bigint": 10 ** 400,
             "bytes": b"x", "generator": (x for x in range(n))}.get(MODE, "__default__")
        return v

    class Metric:
        locals = [("v", "sum", "")]
        needs = ["jacobian"]

        def local_batch(self, q):
            n = q["status"].shape[0]
            if WHERE == "local":
                v = act("local", n)
                if not (isinstance(v, str) and v == "__default__"):
                    return v
            return np.ones((n, 1))

        def combine(self, reduced, samples):
            if WHERE == "combine":
                v = act("combine", 0)
                if not (isinstance(v, str) and v == "__default__"):
                    return v
            return float(reduced[0])

    if MODE == "bad-locals": Metric.locals = "v"
    if MODE == "bad-locals-none": Metric.locals = None
    if MODE == "bad-needs": Metric.needs = 5
    if MODE == "bad-needs-name": Metric.needs = ["no_such_quantity"]
    study = hapsyn.load(prob, metrics={"%(name)s": Metric})
    S["study"] = study
    if CALL == "evaluate":
        r = study.evaluate([])
        report["result"] = {"status": r.get("status"), "objectives": {k: float(v) for k, v in r.get("objectives", {}).items()}}
    elif CALL == "evaluate-threads":
        r = study.evaluate([], threads=2)
        report["result"] = {"status": r.get("status")}
    elif CALL == "progress":
        r = study.run(threads=1, progress=lambda line: act("progress", 1))
        report["result"] = {"status": r.status}
    else:
        r = study.run(threads=1)
        report["result"] = {"status": r.status, "objectives": {k: float(v) for k, v in (r.best_objectives or {}).items()}}
except BaseException as e:  # KeyboardInterrupt and SystemExit too: reported, not a signal exit
    report = {"kind": "exception", "type": type(e).__name__, "module": type(e).__module__, "message": str(e)[:2000],
              "traceback": traceback.format_exc()[-2000:]}
print("ATTACK-REPORT " + json.dumps(report), flush=True)
''' % {"name": PY_METRIC}

# (mode, where, call, expect, cause). expect: error (a hapsyn.Error naming the metric), own (the
# exception raised in the callback, as itself), error-or-ok (a clear error or a right answer), any.
PY_FIXED = [
    ("reenter-evaluate", "local", "evaluate", "error-or-ok", "python: metric re-enters its study (deadlock)"),
    ("str", "combine", "evaluate", "error", "python: metric returns a wrong type (raw pybind11 cast error)"),
    ("none", "local", "evaluate", "error", "python: metric returns a wrong type"),
    ("reenter-run", "local", "run", "error-or-ok", "python: metric re-enters its study (deadlock)"),
    ("raise", "local", "run", "own", "python: exception inside a metric"),
    ("keyboard", "local", "run", "own", "python: KeyboardInterrupt inside a metric"),
    ("none", "combine", "run", "error", "python: metric returns a wrong type (raw pybind11 cast error)"),
    ("list-long", "local", "evaluate", "error", "python: metric returns a wrong type"),
    ("reenter-evaluate", "combine", "evaluate", "error-or-ok", "python: metric re-enters its study (deadlock)"),
    ("shape", "local", "evaluate-threads", "error", "python: metric returns a wrong type"),
    ("nan", "local", "evaluate", "error", "python: metric returns NaN"),
    ("nan", "combine", "run", "error", "python: metric returns NaN"),
    ("strarr", "local", "evaluate", "error", "python: metric returns a wrong type"),
    ("objarr", "local", "evaluate", "error", "python: metric returns a wrong type"),
    ("array2", "combine", "evaluate", "error", "python: metric returns a wrong type (raw pybind11 cast error)"),
    ("raise", "combine", "evaluate", "own", "python: exception inside a metric"),
    ("keyboard", "combine", "evaluate", "own", "python: KeyboardInterrupt inside a metric"),
    ("reenter-evaluate", "progress", "progress", "error-or-ok", "python: progress callback re-enters its study"),
    ("load-inside", "local", "evaluate", "any", "python: a study loaded inside a metric"),
    ("bad-locals", "local", "evaluate", "error", "python: metric class attributes of wrong types"),
    ("bad-needs", "local", "evaluate", "error", "python: metric class attributes of wrong types"),
    ("systemexit", "local", "run", "own", "python: SystemExit inside a metric"),
    ("complex", "local", "evaluate", "any", "python: metric returns complex values"),
    ("inf", "combine", "evaluate", "error", "python: metric returns a non-finite value"),
]
PY_MODES = ["str", "none", "list-long", "list-short", "shape", "shape3d", "strarr", "objarr", "nan", "dict", "bool", "int",
            "tuple", "array2", "inf", "bigint", "bytes", "generator", "raise", "keyboard", "reenter-evaluate",
            "reenter-run", "bad-locals-none", "bad-needs-name"]
PY_OWN = {"raise": "KeyError", "keyboard": "KeyboardInterrupt", "systemexit": "SystemExit"}


def python_expect(mode: str, where: str) -> str:
    if mode in PY_OWN:
        return "own"
    if mode.startswith("reenter"):
        return "error-or-ok"
    if mode in ("int", "bool") and where == "combine":
        return "any"  # a number is a fine combined value
    if mode in ("bool", "int", "complex") and where == "local":
        return "any"
    return "error"


def case_python(ctx, case, sb):
    p = case.params
    mode, where, call, expect = p["mode"], p["where"], p["call"], p["expect"]
    script = sb.cwd / "attack_python.py"
    script.write_text(PY_SCRIPT)
    prob = sb.cwd / "study.json"
    doc = json.loads(MEAN_ISOTROPY_STUDY.read_text())
    doc.pop("output", None)
    prob.write_text(json.dumps(doc))
    py = "/usr/bin/python3" if os.access("/usr/bin/python3", os.X_OK) else sys.executable
    env = {"PYTHONPATH": str(Path(ctx.hapsyn).resolve().parents[1] / "python"), "PYTHONDONTWRITEBYTECODE": "1"}
    t0 = time.monotonic()
    proc, cmd, argv = start_cmd(ctx, sb, [py, str(script), mode, where, call, str(prob)], env)
    r = A.finish(proc, cmd, argv, min(ctx.args.timeout, 15.0), t0)  # the script itself takes ~1 s
    what = f"metric {mode} in {where}, via {call}"
    if r.timed_out:
        return A.outcome(r, "hang", f"{what}: no exit within {r.timeout:.0f} s (deadlock?)")
    if r.rc is not None and r.rc < 0:
        return A.outcome(r, *A.classify(r))
    m = re.search(r"^ATTACK-REPORT (.*)$", r.out, re.M)
    if not m:
        return A.outcome(r, "internal", f"{what}: exit {r.rc} without a report: {A.first_error_line(r.err)}")
    rep = json.loads(m.group(1))
    if rep["kind"] == "import-error":
        return A.outcome(r, "skip", f"{what}: cannot import hapsyn (build in progress?): {rep['message'][:200]}")
    if rep["kind"] == "ok":
        res = rep.get("result", {})
        if expect == "error":
            return A.outcome(r, "wrong", f"{what}: accepted ({json.dumps(res)[:200]}) but must raise a hapsyn error")
        if expect == "own":
            return A.outcome(r, "wrong", f"{what}: the exception raised in the callback was swallowed: {json.dumps(res)[:200]}")
        return A.outcome(r, "ok", f"{what}: {json.dumps(res)[:200]}")
    etype, emod, msg = rep["type"], rep["module"], rep["message"]
    shown = f"{emod}.{etype}: {msg[:300]}"
    if "Unable to cast" in msg or "pybind11" in msg:
        return A.outcome(r, "internal", f"{what}: a raw pybind11 error: {shown}")
    if expect == "own":
        if etype == PY_OWN[mode]:
            return A.outcome(r, "ok", f"{what}: {shown}")
        return A.outcome(r, "internal", f"{what}: {PY_OWN[mode]} raised in the callback came back as {shown}")
    if etype == "Error" and emod.startswith("hapsyn") and (PY_METRIC in msg or "objectives[0]" in msg or
                                                            where == "progress" or mode.startswith("reenter")):
        return A.outcome(r, "ok", f"{what}: {shown}")
    if mode.startswith("reenter") and "hapsyn" in emod and msg:
        return A.outcome(r, "ok", f"{what}: {shown}")
    if etype == "Error" and emod.startswith("hapsyn"):
        return A.outcome(r, "internal", f"{what}: a hapsyn.Error that does not name the metric: {shown}")
    return A.outcome(r, "internal", f"{what}: not a hapsyn error naming the metric: {shown}")


def gen_python(seed: int, n: int) -> list:
    rng = random.Random(f"{seed}:python")
    cases = []
    for i in range(n):
        if i < len(PY_FIXED):
            mode, where, call, expect, cause = PY_FIXED[i]
        else:
            mode = rng.choice(PY_MODES)
            where = rng.choice(["local", "combine"]) if not mode.startswith("bad") else "local"
            call = rng.choice(["evaluate", "evaluate-threads", "run"])
            expect = python_expect(mode, where)
            cause = ("python: metric re-enters its study (deadlock)" if mode.startswith("reenter")
                     else f"python: metric misuse ({mode})")
        cases.append(A.Case("python", i, f"{mode}@{where}/{call}", cause, case_python,
                            {"mode": mode, "where": where, "call": call, "expect": expect}))
    return cases


# ------------------------------------------------------------------------------------------------
# Class shares: --shard runs merged with `hapsyn merge`, shares tampered with.

def shares_problem(step=0.01, upper=0.30) -> dict:
    doc = urdf_problem(PHANTOM_URDF, {})
    doc["name"] = "attack-shares"
    doc["objectives"] = [{"metric": "gii", "sense": "maximize"}]
    doc["design"] = {"elbow_joint:x": {"lower": 0.15, "upper": upper, "step": step},
                     "gimbal_center_joint:z": {"lower": -0.30, "upper": -0.10, "step": 0.01}}
    doc["solver"] = {"plugin": "grid"}
    return doc


SHARE_STUDIES = {"main": (shares_problem(), 3, []), "main2": (shares_problem(), 2, []),
                 "other": (shares_problem(upper=0.29), 3, []), "seed": (shares_problem(), 3, ["--seed", "7"]),
                 "tiny": (shares_problem(upper=0.16), 3, [])}


def shares_ref(ctx, key: str) -> dict:
    """Shares 1..N and the unsharded control of one study, made once per campaign."""
    doc, n, extra = SHARE_STUDIES[key]

    def make(sb):
        prob = write_problem(sb, doc)
        dirs = []
        for i in range(1, n + 1):
            d = sb.cwd / f"share{i}"
            r = A.run(ctx, sb, ["run", str(prob), "--shard", f"{i}/{n}", "--out", str(d), "--threads", "1", "--quiet"]
                      + extra, timeout=120)
            if r.rc != 0:
                raise RuntimeError(f"shard {i}/{n} of {key} failed ({r.rc}): {A.tail(r.err)}")
            dirs.append(str(d))
        full = sb.cwd / "full"
        r = A.run(ctx, sb, ["run", str(prob), "--out", str(full), "--threads", "1", "--quiet"] + extra, timeout=120)
        if r.rc != 0:
            raise RuntimeError(f"the unsharded run of {key} failed ({r.rc}): {A.tail(r.err)}")
        return {"dirs": dirs, "full": str(full), "problem": str(prob)}
    return reference(ctx, "shares-" + key, make)


def merged_differs(out: Path, full: Path) -> list:
    a, b = A.result_of(out), A.result_of(full)
    if a is None:
        return ["no readable result.json"]
    diffs = []
    for k in ("status", "best", "front", "seed"):
        if a.get(k) != b.get(k):
            diffs.append(f"{k} {json.dumps(a.get(k))[:120]} != control {json.dumps(b.get(k))[:120]}")
    for f in ("samples.csv", "maps.csv"):
        if A.sha(out / f) != A.sha(full / f):
            diffs.append(f"{f} differs from the unsharded run's")
    return diffs


def tamper(rng: random.Random, kind: str, dirs: list, other) -> tuple:
    """Applies `kind` to copies of the shares: (merge arguments (dirs), extra flags, what, expect);
    other(key) gives the shares of another study (shares_ref)."""
    d = Path(rng.choice(dirs))
    res = d / "result.json"
    if kind == "control":
        return dirs, [], "the pristine shares", "equal"
    if kind == "control-one-chunk":
        return dirs, [], "the pristine shares of a 42-design grid (one chunk: two shares are empty)", "equal"
    if kind == "control-two":
        return dirs, [], "the pristine 2 shares", "equal"
    if kind in ("shard-string", "shard-array", "shard-field-type", "result-wrongtype"):
        doc = json.loads(res.read_text())
        if kind == "shard-string":
            key = rng.choice(["index", "count"])
            doc["shard"][key] = str(doc["shard"][key])
            what = f"{d.name}: shard.{key} a string"
        elif kind == "shard-array":
            doc["shard"] = [doc["shard"]]
            what = f"{d.name}: shard an array holding the object"
        elif kind == "shard-field-type":
            key = rng.choice(["complete", "problem_document", "problem_file", "index"])
            v = rng.choice([v for v in ["yes", 1, None, [], {}, 1.5, -1] if type(v) is not type(doc["shard"].get(key))])
            doc["shard"][key] = v
            what = f"{d.name}: shard.{key} = {json.dumps(v)}"
            if key in ("problem_document", "problem_file"):  # read from the first share only
                res.write_text(json.dumps(doc, indent=1))
                return dirs, [], what, "equal-or-refuse"
        else:
            key = rng.choice(["seed", "hapsyn", "problem", "status"])
            v = rng.choice(["1", [], {}, None, 1.5, -1, "x"])
            doc[key] = v
            what = f"{d.name}: {key} = {json.dumps(v)}"
        res.write_text(json.dumps(doc, indent=1))
        return dirs, [], what, ("equal-or-refuse" if what.split(": ")[1].startswith("status") else "refuse")
    if kind == "delete-field":
        doc = json.loads(res.read_text())
        key = rng.choice(["shard", "shard.index", "shard.count", "shard.complete", "seed", "hapsyn", "problem",
                          "shard.problem_document", "hapsyn.version"])
        parts = key.split(".")
        obj = doc
        for p in parts[:-1]:
            obj = obj[p]
        obj.pop(parts[-1], None)
        res.write_text(json.dumps(doc, indent=1))
        return dirs, [], f"{d.name}: result.json {key} deleted", "refuse"
    if kind == "study-hash":
        cp = d / "checkpoint.json"
        doc = json.loads(cp.read_text())
        fp = doc["fingerprint"]
        doc["fingerprint"] = fp[:-1] + ("0" if fp[-1] != "0" else "1")
        cp.write_text(json.dumps(doc))
        return dirs, [], f"{d.name}: checkpoint fingerprint changed", "refuse"
    if kind == "checkpoint-wrongtype":
        cp = d / "checkpoint.json"
        doc = json.loads(cp.read_text())
        key = rng.choice(["fingerprint", "solver", "state", "seed", "version"])
        v = rng.choice([x for x in [1, [], {}, None, "x"] if x != doc.get(key)])  # a change, never the value itself
        doc[key] = v
        cp.write_text(json.dumps(doc))
        return dirs, [], f"{d.name}: checkpoint.json {key} = {json.dumps(v)}", "refuse"
    if kind in ("foreign-share", "other-seed"):
        other = other("other" if kind == "foreign-share" else "seed")
        i = rng.randrange(len(dirs))
        target = Path(dirs[i])
        shutil.rmtree(target)
        shutil.copytree(other["dirs"][i], target)
        what = f"share {i + 1} replaced by share {i + 1} of " + ("another study" if kind == "foreign-share" else "seed 7")
        return dirs, [], what, "refuse"
    if kind == "duplicate":
        v = rng.choice(["same-dir", "copy"])
        i = rng.randrange(len(dirs))
        if v == "same-dir":
            return dirs + [dirs[i]], [], f"share {i + 1} given twice", "refuse"
        cp = str(Path(dirs[i]).parent / "copy")
        shutil.copytree(dirs[i], cp)
        return dirs + [cp], [], f"a copy of share {i + 1} given as well", "refuse"
    if kind == "missing-share":
        i = rng.randrange(len(dirs))
        return dirs[:i] + dirs[i + 1:], [], f"share {i + 1} left out", "refuse"
    if kind in ("out-is-share", "out-in-share"):
        i = rng.randrange(len(dirs))
        out = dirs[i] if kind == "out-is-share" else str(Path(dirs[i]) / "sub")
        return dirs, ["--out", out, "--force"], f"--out {'=' if kind == 'out-is-share' else 'inside'} share {i + 1}, --force", \
            "refuse-keep"
    if kind == "truncate-csv":
        f = d / rng.choice(["samples.csv", "maps.csv"])
        data = f.read_bytes()
        f.write_bytes(data[:rng.randrange(len(data))])
        return dirs, [], f"{d.name}/{f.name} truncated", "equal-or-refuse"
    if kind == "truncate-json":
        f = d / rng.choice(["result.json", "checkpoint.json"])
        data = f.read_bytes()
        f.write_bytes(data[:rng.randrange(len(data))])
        return dirs, [], f"{d.name}/{f.name} truncated", "refuse"
    if kind == "remove-file":
        f = d / rng.choice(["result.json", "checkpoint.json", "samples.csv", "run.log"])
        f.unlink()
        return dirs, [], f"{d.name}/{f.name} removed", ("equal-or-refuse" if f.suffix in (".csv", ".log") else "refuse")
    if kind == "unfinished":
        doc = json.loads(res.read_text())
        doc["shard"]["complete"] = False
        res.write_text(json.dumps(doc, indent=1))
        return dirs, [], f"{d.name}: shard.complete = false", "refuse"
    if kind == "random-edit":
        f = d / rng.choice(["result.json", "checkpoint.json"])
        doc = json.loads(f.read_text())
        if f.name == "checkpoint.json" and isinstance(doc.get("state"), str):
            doc["state"] = json.loads(doc["state"])
        paths = [p for p in A.all_paths(doc) if p]
        p = rng.choice(paths)
        old = A.get_at(doc, p)
        v = rng.choice([v for v in [0, -1, 1e300, "x", True, None, [], {}] if type(v) is not type(old)])
        A.set_at(doc, p, v)
        f.write_text(json.dumps(doc))
        return dirs, [], f"{d.name}/{f.name}: {A.set_path_text(p)} = {json.dumps(v)} (was {type(old).__name__})", \
            "equal-or-refuse"
    raise ValueError(kind)



def case_shares(ctx, case, sb):
    rng = random.Random(case.params["rng"])
    key = {"control-one-chunk": "tiny", "control-two": "main2"}.get(case.kind, case.params.get("study", "main"))
    ref = shares_ref(ctx, key)
    dirs = []
    for i, src in enumerate(ref["dirs"]):
        dst = sb.cwd / f"share{i + 1}"
        shutil.copytree(src, dst)
        dirs.append(str(dst))
    args, flags, what, expect = tamper(rng, case.kind, dirs, lambda k: shares_ref(ctx, k))
    out = sb.cwd / "merged"
    before = {f: A.sha(Path(f)) for dd in dirs for f in map(str, Path(dd).glob("*")) if Path(f).is_file()}
    r = A.run(ctx, sb, ["merge"] + [str(a) for a in args] + (flags or ["--out", str(out)]) + ["--threads", "1", "--quiet"])
    c, d = A.classify(r, "refuse" if expect.startswith("refuse") else "any")
    checks = [(c, d)]
    if r.rc == 0 and not flags:
        diffs = merged_differs(out, Path(ref["full"]))
        if diffs:
            checks.append(("wrong", "merged result differs from the unsharded run: " + "; ".join(diffs[:3])))
    if expect == "equal" and r.rc not in (0, None) and not r.timed_out and c == "ok":
        checks.append(("wrong", "pristine shares refused: " + A.first_error_line(r.err)))
    if expect == "refuse-keep":
        changed = [os.path.relpath(f, sb.cwd) for f, h in before.items() if A.sha(Path(f)) != h]
        if changed:
            checks.append(("wrong", "files of the share were written over: " + ", ".join(changed[:3])))
    if r.rc is not None and r.rc >= 0 and not r.timed_out and not flags:
        probs = A.out_dir_problems(out, True)
        if probs:
            checks.append(("mixed", "; ".join(probs)))
    cat, det = A.worst(*checks)
    return A.outcome(r, cat, what + (": " + det if det else ""))


SHARES_FIXED = ["control", "shard-string", "out-is-share", "study-hash", "foreign-share", "shard-array", "delete-field",
                "duplicate", "truncate-csv", "control-one-chunk", "other-seed", "out-in-share", "missing-share",
                "unfinished", "checkpoint-wrongtype", "result-wrongtype", "truncate-json", "remove-file", "control-two",
                "shard-field-type"]
SHARES_RANDOM = ["shard-string", "shard-field-type", "result-wrongtype", "delete-field", "checkpoint-wrongtype",
                 "truncate-csv", "truncate-json", "remove-file", "random-edit", "random-edit", "random-edit", "duplicate",
                 "missing-share"]
SHARES_CAUSE = {"shard-string": "merge: wrong-typed share field (exit 3)", "shard-array": "merge: wrong-typed share field (exit 3)",
                "shard-field-type": "merge: wrong-typed share field (exit 3)",
                "result-wrongtype": "merge: wrong-typed share field (exit 3)",
                "checkpoint-wrongtype": "merge: wrong-typed share field (exit 3)",
                "control-one-chunk": "shard: a share that ran the whole job keeps no checkpoint"}


def gen_shares(seed: int, n: int) -> list:
    rng = random.Random(f"{seed}:shares")
    cases = []
    for i in range(n):
        kind = SHARES_FIXED[i] if i < len(SHARES_FIXED) else rng.choice(SHARES_RANDOM)
        cases.append(A.Case("shares", i, kind, SHARES_CAUSE.get(kind, f"merge: {kind}"), case_shares,
                            {"rng": f"{seed}:shares:{i}", "study": "main" if i < len(SHARES_FIXED) or rng.random() < 0.7
                             else "main2"}))
    return cases
