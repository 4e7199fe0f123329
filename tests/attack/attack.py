#!/usr/bin/env python3
"""hapsyn attack campaign: hostile inputs per class against the built `hapsyn` binary.

Every input is generated deterministically from (--seed, class, index), run in its own sandbox
directory with a timeout, and classified:

  ok        exit 0, or exit 1 with a clear "hapsyn: error: <component>: ..." (exit 2: CLI usage)
  crash     killed by a signal (or a sanitizer report)
  hang      no exit within the timeout (or the bound of the class, e.g. a stop request)
  internal  exit 3, "internal error", exit 1 without a clear message, any other exit status
  wrong     success where the oracle says it must be refused, or a value known to be wrong
  mixed     the output directory left inconsistent, or files written outside it
  skip      the case cannot run here (e.g. not root for the tmpfs case); not a failure

Standard library only. See tests/attack/README.md for the classes and their oracles.
"""
from __future__ import annotations

import argparse
import concurrent.futures
import dataclasses
import hashlib
import json
import os
import random
import re
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Callable, Optional

ROOT = Path(__file__).resolve().parents[2]
PROBLEMS = ROOT / "problems"
CATEGORIES = ["ok", "crash", "hang", "internal", "wrong", "mixed"]
SEVERITY = {"crash": 6, "hang": 5, "internal": 4, "wrong": 3, "mixed": 2, "skip": 1, "ok": 0}
# `hapsyn run` stopped on request (SIGINT, SIGTERM, SIGUSR1): result.json status "stopped".
EXIT_STOPPED = 4

CLASSES = ["json", "set", "cli", "output", "checkpoint", "cache", "plugins", "signal"]
CLEAR_ERROR = re.compile(r"^hapsyn: error: [A-Za-z0-9_.\-]+(?: [A-Za-z0-9_.\-']+)?: \S", re.M)
SANITIZER = re.compile(r"AddressSanitizer|UndefinedBehaviorSanitizer|runtime error:|LeakSanitizer|ThreadSanitizer")
CSV_NAMES = ("samples.csv", "maps.csv", "groups.csv")

# Outputs of the output-safety study (evaluate the Table 2 design on a fine square workspace:
# the samples and maps CSVs are large enough that writing them takes a measurable time).
OUT_PROBLEM = "fivebar-table2-best-gii.json"
OUT_A = ["scene.options.step=0.0005"]
OUT_B = ["scene.options.step=0.0004"]
# A GA study that checkpoints every generation and runs a few seconds.
GA_PROBLEM = "fivebar-gii-ga-coarse.json"
GA_SETS = ["solver.options.population=16", "solver.options.generations=1500", "solver.options.stall_generations=1500",
           "solver.options.ftol=0", "solver.options.checkpoint_every=1"]
# A tiny human_arm scene (seconds to build).
ARM_PROBLEM = "haptic6r-ga-quick.json"
ARM_SETS = ["scene.options.lattice_step=0.35", "scene.options.orientations=7", "scene.options.joint3_steps=3"]


# ------------------------------------------------------------------------------------------------
# Shell quoting for one-line reproductions (bytes arguments become $'...').

def shq(a) -> str:
    b = a if isinstance(a, bytes) else os.fsencode(str(a))
    if b and re.fullmatch(rb"[A-Za-z0-9_./=:,+@%-]+", b):
        return b.decode()
    if all(32 <= c < 127 for c in b) and b"'" not in b:
        return "'" + b.decode() + "'"
    out = []
    for c in b:
        if c in (ord("'"), ord("\\")):
            out.append("\\" + chr(c))
        elif 32 <= c < 127:
            out.append(chr(c))
        else:
            out.append("\\x%02x" % c)
    return "$'" + "".join(out) + "'"


def shline(argv, env_extra=None, cwd=None, limit=600) -> str:
    parts = []
    if cwd:
        parts.append("cd " + shq(cwd) + " &&")
    for k, v in (env_extra or {}).items():
        parts.append(f"{k}={shq(v)}")
    for a in argv:
        q = shq(a)
        if len(q) > limit:
            q = q[:limit // 2] + f"...<{len(q)} chars>"
        parts.append(q)
    return " ".join(parts)


# ------------------------------------------------------------------------------------------------
# Cases, outcomes, sandboxes, running the binary.

@dataclasses.dataclass
class Outcome:
    category: str
    detail: str = ""
    cmd: str = ""
    rc: Optional[int] = None
    elapsed: float = 0.0
    stderr_tail: str = ""


@dataclasses.dataclass
class Case:
    cls: str
    index: int
    kind: str
    cause: str
    fn: Callable
    params: dict

    @property
    def cid(self) -> str:
        return f"{self.cls}-{self.index:04d}"


@dataclasses.dataclass
class Res:
    argv: list
    rc: Optional[int]
    out: str
    err: str
    elapsed: float
    timed_out: bool
    timeout: float
    cmd: str


class Sandbox:
    """A case's directory: root/d1/d2/d3/cwd is the working directory, so a name like ../../x
    resolves inside root and can be detected."""

    def __init__(self, root: Path):
        self.root = root
        self.cwd = root / "d1" / "d2" / "d3" / "cwd"
        self.cwd.mkdir(parents=True)

    def snapshot(self) -> dict:
        snap = {}
        for dirpath, dirnames, filenames in os.walk(self.root, followlinks=False):
            for n in dirnames + filenames:
                p = os.path.join(dirpath, n)
                try:
                    st = os.lstat(p)
                except OSError:
                    continue
                snap[p] = (stat.S_IFMT(st.st_mode), st.st_size, st.st_mtime_ns)
            # Do not descend into mount points (the tmpfs of the full-filesystem case) twice.
        return snap


class Ctx:
    def __init__(self, args):
        self.args = args
        self.hapsyn = str(Path(args.hapsyn).resolve())
        self.work = Path(args.work).resolve()
        self.lock = threading.Lock()
        self.shared = {}
        self.shared_locks = {}
        self.is_root = os.geteuid() == 0
        home = self.work / "home"
        (home / ".cache").mkdir(parents=True, exist_ok=True)
        self.env = {k: v for k, v in os.environ.items() if not k.startswith("HAPSYN_")}
        self.env.update({"HOME": str(home), "XDG_CACHE_HOME": str(home / ".cache"), "LC_ALL": "C",
                         "ASAN_OPTIONS": "detect_leaks=0:abort_on_error=0"})
        self.prlimit = shutil.which("prlimit")

    def once(self, key: str, make: Callable):
        """Computes a shared reference (a checkpoint, a reference run) once per campaign."""
        with self.lock:
            lk = self.shared_locks.setdefault(key, threading.Lock())
        with lk:
            if key not in self.shared:
                try:
                    self.shared[key] = ("value", make())
                except Exception as e:  # noqa: BLE001 - recorded and re-raised for every user
                    self.shared[key] = ("error", f"{type(e).__name__}: {e}")
            kind, value = self.shared[key]
        if kind == "error":
            raise SetupError(f"setup '{key}' failed: {value}")
        return value


class SetupError(Exception):
    pass


def problem(name: str) -> str:
    return str(PROBLEMS / name)


def with_sets(sets) -> list:
    argv = []
    for s in sets:
        argv += ["--set", s]
    return argv


def start(ctx: Ctx, sb: Sandbox, args: list, env_extra=None, cwd=None):
    env = dict(ctx.env)
    env.update(env_extra or {})
    argv = [ctx.hapsyn] + list(args)
    full = argv
    if ctx.prlimit and ctx.args.mem_mb > 0:
        full = [ctx.prlimit, f"--as={ctx.args.mem_mb * 1024 * 1024}", "--"] + argv
    p = subprocess.Popen(full, cwd=str(cwd or sb.cwd), env=env, stdin=subprocess.DEVNULL,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    cmd = shline(full, env_extra, cwd or sb.cwd)
    return p, cmd, argv


def finish(p, cmd, argv, timeout, t0=None) -> Res:
    t0 = t0 or time.monotonic()
    timed_out = False
    try:
        out, err = p.communicate(timeout=max(0.1, timeout - (time.monotonic() - t0)))
    except subprocess.TimeoutExpired:
        timed_out = True
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except OSError:
            pass
        out, err = p.communicate()
    return Res(argv, p.returncode, out.decode("utf-8", "replace"), err.decode("utf-8", "replace"),
               time.monotonic() - t0, timed_out, timeout, cmd)


def run(ctx: Ctx, sb: Sandbox, args: list, timeout=None, env_extra=None, cwd=None) -> Res:
    timeout = timeout or ctx.args.timeout
    t0 = time.monotonic()
    p, cmd, argv = start(ctx, sb, args, env_extra, cwd)
    return finish(p, cmd, argv, timeout, t0)


def tail(s: str, n=400) -> str:
    s = s.strip()
    return s if len(s) <= n else "..." + s[-n:]


def first_error_line(err: str) -> str:
    for line in err.splitlines():
        if "error" in line or "Error" in line or "terminate" in line:
            return line.strip()[:300]
    return tail(err, 200).replace("\n", " | ")


def classify(r: Res, expect="any") -> tuple:
    """(category, detail) of one run. expect: any, refuse, accept."""
    if r.timed_out:
        return "hang", f"no exit within {r.timeout:.0f} s"
    if SANITIZER.search(r.err):
        return "crash", "sanitizer: " + first_error_line(r.err)
    if r.rc is not None and r.rc < 0:
        try:
            name = signal.Signals(-r.rc).name
        except ValueError:
            name = str(-r.rc)
        return "crash", f"killed by {name}" + (f" ({first_error_line(r.err)})" if r.err.strip() else "")
    if r.rc == 3 or "internal error" in r.err:
        return "internal", f"exit {r.rc}: {first_error_line(r.err)}"
    if r.rc == 0:
        if expect == "refuse":
            return "wrong", "accepted (exit 0) but must be refused"
        return "ok", ""
    if r.rc == 1:
        if not CLEAR_ERROR.search(r.err):
            return "internal", "exit 1 without a clear 'hapsyn: error: <component>: ...' message: " + tail(r.err, 200)
        if expect == "accept":
            return "wrong", "refused but must be accepted: " + first_error_line(r.err)
        return "ok", first_error_line(r.err)
    if r.rc == 2:
        if not r.err.strip():
            return "internal", "exit 2 (usage) without a message"
        if expect == "accept":
            return "wrong", "usage error but must be accepted: " + first_error_line(r.err)
        return "ok", "usage: " + first_error_line(r.err)
    return "internal", f"unexpected exit status {r.rc}: {first_error_line(r.err)}"


def outcome(r: Res, category: str, detail: str) -> Outcome:
    return Outcome(category, detail, r.cmd, r.rc, r.elapsed, tail(r.err))


def worst(*pairs) -> tuple:
    cat, details = "ok", []
    for c, d in pairs:
        if c != "ok" and d:
            details.append(d)
        if SEVERITY[c] > SEVERITY[cat]:
            cat = c
    if cat == "ok":
        details = [d for c, d in pairs if d][:1]
    return cat, "; ".join(details)


# ------------------------------------------------------------------------------------------------
# Output-directory checks.

def out_dir_problems(out: Path, clean_exit: bool) -> list:
    """Inconsistencies of an output directory: CSVs without result.json, CSVs result.json does
    not name (left by another run), files it names that are missing, leftover temporaries."""
    problems = []
    try:
        if not out.is_dir():
            return problems
        names = set(os.listdir(out))
    except OSError:
        return problems
    csvs = sorted(n for n in names if n in CSV_NAMES)
    if csvs and "result.json" not in names:
        problems.append(f"{', '.join(csvs)} without result.json")
    if "result.json" in names:
        try:
            doc = json.loads((out / "result.json").read_bytes())
        except (OSError, ValueError) as e:
            problems.append(f"result.json unreadable ({e.__class__.__name__})")
            doc = None
        if isinstance(doc, dict) and isinstance(doc.get("files"), dict):
            files = doc["files"]
            listed = {v for v in files.values() if isinstance(v, str)}
            for c in csvs:
                if c not in listed:
                    problems.append(f"{c} beside a result.json that does not name it (left by another run)")
            for f in listed:
                if f.endswith(".csv") and f not in names:
                    problems.append(f"result.json names {f}, which is missing")
    if clean_exit:
        temps = sorted(n for n in names if re.search(r"\.tmp|~$|\.part$|\.new$", n))
        if temps:
            problems.append("temporary files left after the process ended: " + ", ".join(temps[:5]))
    return problems


def outside_writes(before: dict, after: dict, allowed: list) -> list:
    allowed = [os.path.abspath(a) for a in allowed]

    def ok(p):
        for a in allowed:
            if p == a or p.startswith(a + os.sep):
                return True
            if a.startswith(p + os.sep) and after.get(p, (0,))[0] == stat.S_IFDIR:
                return True  # an ancestor directory of the output directory
        return False

    bad = []
    for p, v in after.items():
        if ok(p):
            continue
        old = before.get(p)
        if old is None or (v[0] != stat.S_IFDIR and old != v):
            bad.append(p)
    return sorted(bad)


def leftover_temps(before: dict, after: dict) -> list:
    """Temporary files (of atomic writes) that appeared and were not cleaned up."""
    return sorted(p for p in after if p not in before and re.search(r"(^|/)\.tmp-|\.tmp$|\.part$", p))


def sha(path: Path) -> Optional[str]:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


def result_of(out: Path) -> Optional[dict]:
    try:
        d = json.loads((out / "result.json").read_bytes())
        return d if isinstance(d, dict) else None
    except (OSError, ValueError):
        return None


# ------------------------------------------------------------------------------------------------
# JSON helpers: a dumper that can emit raw (possibly invalid) text and duplicate keys.

class Raw:
    def __init__(self, text: bytes):
        self.text = text


class Pairs:
    def __init__(self, items: list):
        self.items = items


def jdump(v) -> bytes:
    if isinstance(v, Raw):
        return v.text
    if isinstance(v, Pairs):
        return b"{" + b", ".join(jdump(k) + b": " + jdump(x) for k, x in v.items) + b"}"
    if isinstance(v, dict):
        return b"{\n" + b",\n".join(jdump(k) + b": " + jdump(x) for k, x in v.items()) + b"\n}"
    if isinstance(v, list):
        return b"[" + b", ".join(jdump(x) for x in v) + b"]"
    return json.dumps(v, ensure_ascii=False).encode()


def all_paths(doc, prefix=()) -> list:
    out = [prefix]
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += all_paths(v, prefix + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += all_paths(v, prefix + (i,))
    return out


def get_at(doc, path):
    for k in path:
        doc = doc[k]
    return doc


def set_at(doc, path, value):
    if not path:
        return value
    get_at(doc, path[:-1])[path[-1]] = value
    return doc


def set_path_text(path) -> str:
    return ".".join(str(k) for k in path)


def deep(depth: int, kind: str, close=True) -> bytes:
    if kind == "array":
        return b"[" * depth + (b"1" + b"]" * depth if close else b"")
    return b'{"a":' * depth + (b"1" + b"}" * depth if close else b"")


HOSTILE_VALUES = [
    "0", "-0", "-1", "1e-20", "1e400", "-1e400", "4294967297", "-4294967297", "18446744073709551616",
    "9223372036854775807", "1.7976931348623157e308", "5e-324", "NaN", "Infinity", "null", "true", "[]", "{}",
    '""', "[1e308,1e308]", '{"plugin":"x"}', "../../x", "y.so/../payload", b"\xff\xfe", b"caf\xe9",
    "[" * 20000 + "]" * 20000, '{"a":' * 20000 + "1" + "}" * 20000, "[" * 20000, "x" * 100000,
]


# ------------------------------------------------------------------------------------------------
# Class json: mutated problem files, validated.

JSON_MUTATIONS = ["flip", "truncate", "deep", "deep-unclosed", "hugenum", "negzero", "hugestr", "badutf8", "dupkey",
                  "wrongtype", "empty", "delete", "nan", "garbage", "keyutf8", "ctrl", "bigarray", "bom"]
JSON_REFUSE = {"truncate": "refuse", "deep-unclosed": "refuse", "badutf8": "refuse", "dupkey": "refuse",
               "nan": "refuse", "garbage": "refuse", "keyutf8": "refuse", "ctrl": "refuse"}
JSON_CAUSE = {"deep": "loader: deep JSON nesting", "deep-unclosed": "loader: deep JSON nesting",
              "dupkey": "loader: duplicate keys accepted", "badutf8": "loader: invalid UTF-8",
              "keyutf8": "loader: invalid UTF-8", "hugenum": "loader: huge numbers",
              "hugestr": "loader: huge strings", "bigarray": "loader: huge arrays"}


def json_problems() -> list:
    files = sorted(p.name for p in PROBLEMS.glob("*.json"))
    fast = [f for f in files if f.startswith("fivebar")]
    # The five-bar studies validate in milliseconds: three of four inputs come from them.
    return fast * 3 + files


def mutate_json(rng: random.Random, text: bytes, kind: str) -> tuple:
    doc = json.loads(text)
    paths = all_paths(doc)
    value_paths = [p for p in paths if p]
    numbers = [p for p in value_paths if isinstance(get_at(doc, p), (int, float)) and not isinstance(get_at(doc, p), bool)]
    strings = [p for p in value_paths if isinstance(get_at(doc, p), str)]
    objects = [p for p in paths if isinstance(get_at(doc, p), dict) and get_at(doc, p)]
    containers = [p for p in value_paths if isinstance(get_at(doc, p), (dict, list))]
    what = ""
    if kind == "flip":
        b = bytearray(text)
        for _ in range(rng.randint(1, 8)):
            i = rng.randrange(len(b))
            b[i] ^= rng.randint(1, 255)
        return bytes(b), "bytes flipped"
    if kind == "truncate":
        body = text.rstrip()
        n = rng.randrange(1, len(body) - 1)
        return text[:n], f"truncated at byte {n} of {len(text)}"
    if kind in ("deep", "deep-unclosed"):
        depth = rng.choice([1000, 10000, 50000, 50000, 500000] if kind == "deep" else [10000, 50000, 100000])
        shape = rng.choice(["array", "object"])
        p = rng.choice(value_paths)
        doc = set_at(doc, p, Raw(deep(depth, shape, kind == "deep")))
        what = f"{set_path_text(p)} = {shape}s nested {depth} deep" + ("" if kind == "deep" else ", unclosed")
        return jdump(doc), what
    if kind == "hugenum":
        p = rng.choice(numbers or value_paths)
        v = rng.choice(["1e400", "-1e400", "1" + "0" * 400, "1e-400", "18446744073709551616", "-9223372036854775809",
                        "4.9e-324", "1.7976931348623157e308", "123456789012345678901234567890"])
        doc = set_at(doc, p, Raw(v.encode()))
        return jdump(doc), f"{set_path_text(p)} = {v[:30]}"
    if kind == "negzero":
        p = rng.choice(numbers or value_paths)
        doc = set_at(doc, p, Raw(rng.choice([b"-0", b"-0.0", b"-0e0"])))
        return jdump(doc), f"{set_path_text(p)} = -0"
    if kind == "hugestr":
        p = rng.choice(strings or value_paths)
        n = rng.choice([10 ** 4, 10 ** 6, 10 ** 7])
        doc = set_at(doc, p, "A" * n)
        return jdump(doc), f"{set_path_text(p)} = a string of {n} bytes"
    if kind == "badutf8":
        p = rng.choice(strings or value_paths)
        bad = rng.choice([b"\xff", b"\xc0\xaf", b"\xed\xa0\x80", b"\xf8\x88\x80\x80\x80", b"\xe2\x82", b"\\ud800",
                          b"\\udc00x", b"\xfe\xfe"])
        old = get_at(doc, p)
        s = json.dumps(old if isinstance(old, str) else "x", ensure_ascii=False).encode()
        doc = set_at(doc, p, Raw(s[:-1] + bad + b'"'))
        return jdump(doc), f"{set_path_text(p)}: invalid UTF-8 {bad!r} in a string"
    if kind == "dupkey":
        p = rng.choice(objects)
        obj = get_at(doc, p)
        k = rng.choice(list(obj))
        # Mostly the same value again (a document every reader takes the same way, which must
        # still be refused: the duplicate is ambiguous), else a different value of the same type.
        other = obj[k]
        if rng.random() < 0.4:
            if isinstance(other, bool):
                other = not other
            elif isinstance(other, (int, float)):
                other = other * 2 if other else 1
            elif isinstance(other, str):
                other = other + "x"
        items = list(obj.items())
        items.insert(rng.randrange(len(items) + 1), (k, other))
        doc = set_at(doc, p, Pairs(items))
        return jdump(doc), f"duplicate key {set_path_text(p + (k,))} (second value {json.dumps(other)})"
    if kind == "wrongtype":
        p = rng.choice(value_paths)
        old = get_at(doc, p)
        pool = [0, -1, 1.5, "", "x", True, None, [], {}, [1, 2], {"a": 1}]
        pool = [v for v in pool if type(v) is not type(old)]
        v = rng.choice(pool)
        doc = set_at(doc, p, v)
        return jdump(doc), f"{set_path_text(p)} = {json.dumps(v)} (was {type(old).__name__})"
    if kind == "empty":
        p = rng.choice(containers or value_paths)
        v = rng.choice([{}, []])
        doc = set_at(doc, p, v)
        return jdump(doc), f"{set_path_text(p)} = {json.dumps(v)}"
    if kind == "delete":
        p = rng.choice([q for q in value_paths if isinstance(q[-1], str)])
        del get_at(doc, p[:-1])[p[-1]]
        return jdump(doc), f"{set_path_text(p)} removed"
    if kind == "nan":
        p = rng.choice(numbers or value_paths)
        v = rng.choice([b"NaN", b"Infinity", b"-Infinity", b"nan", b"inf"])
        doc = set_at(doc, p, Raw(v))
        return jdump(doc), f"{set_path_text(p)} = {v.decode()}"
    if kind == "garbage":
        g = rng.choice([b"x", b"{}", b"\x00", b",", b"]"])
        return text + g, f"trailing {g!r}"
    if kind == "keyutf8":
        p = rng.choice(objects)
        items = list(get_at(doc, p).items())
        i = rng.randrange(len(items))
        items[i] = (Raw(b'"' + items[i][0].encode() + b'\xff"'), items[i][1])
        doc = set_at(doc, p, Pairs(items))
        return jdump(doc), f"invalid UTF-8 in a key of {set_path_text(p) or '(root)'}"
    if kind == "ctrl":
        p = rng.choice(strings or value_paths)
        doc = set_at(doc, p, Raw(b'"a\x01b\nc"'))
        return jdump(doc), f"{set_path_text(p)}: raw control characters in a string"
    if kind == "bigarray":
        p = rng.choice(value_paths)
        n = rng.choice([10 ** 5, 10 ** 6])
        doc = set_at(doc, p, Raw(b"[" + b",".join([b"0"] * n) + b"]"))
        return jdump(doc), f"{set_path_text(p)} = an array of {n} zeros"
    if kind == "bom":
        return b"\xef\xbb\xbf" + text, "UTF-8 byte-order mark"
    raise ValueError(kind)


def case_json(ctx: Ctx, case: Case, sb: Sandbox) -> Outcome:
    rng = random.Random(case.params["rng"])
    src = PROBLEMS / case.params["problem"]
    data, what = mutate_json(rng, src.read_bytes(), case.kind)
    f = sb.cwd / "input.json"
    f.write_bytes(data)
    before = sb.snapshot()
    r = run(ctx, sb, ["validate", str(f)])
    cat, det = classify(r, JSON_REFUSE.get(case.kind, "any"))
    bad = outside_writes(before, sb.snapshot(), [])
    mixed = ("mixed", "validate wrote files: " + ", ".join(bad[:3])) if bad else ("ok", "")
    cat, det = worst((cat, det), mixed)
    return outcome(r, cat, f"{case.params['problem']}: {what}: {det}" if det else f"{case.params['problem']}: {what}")


def gen_json(seed: int, n: int) -> list:
    rng = random.Random(f"{seed}:json")
    probs = json_problems()
    cases = []
    for i in range(n):
        kind = JSON_MUTATIONS[i % len(JSON_MUTATIONS)] if i < len(JSON_MUTATIONS) else rng.choice(JSON_MUTATIONS)
        prob = rng.choice(probs)
        cases.append(Case("json", i, kind, JSON_CAUSE.get(kind, f"loader: {kind}"), case_json,
                          {"problem": prob, "rng": f"{seed}:json:{i}"}))
    return cases


# ------------------------------------------------------------------------------------------------
# Class set: --set overrides with hostile values on real keys.

GII = "fivebar-gii-coarse.json"
SET_FIXED = [
    # kind, cause, problem, sets, mode, expect
    ("step-not-dividing", "loader: design step does not divide the range", GII, ["design.l1.step=0.07"], "validate", "refuse"),
    ("zero-weight", "loader: all objective weights zero", GII, ["objectives.0.weight=0"], "validate", "refuse"),
    ("step-tiny", "loader: design grid size overflow", GII, ["design.l1.step=1e-20"], "validate", "refuse"),
    ("threads-overflow", "runner: threads beyond int accepted (truncated)", GII, ["threads=4294967297"], "run", "refuse"),
    ("seed-negative", "runner: negative seed accepted", GII, ["seed=-1"], "run", "refuse"),
    ("name-as-path", "loader: study name used as a path", GII, ["name=../../x", "output={}"], "run-default-out", "contained"),
    ("plugin-name-as-path", "registry: plugin name used as a path", GII, ["mechanism.plugin=y.so/../payload"],
     "validate-payload", "refuse"),
    ("scene-billions-human-arm", "scene: no size cap (billions of poses)", ARM_PROBLEM, ["scene.options.lattice_step=0.005"],
     "validate", "refuse"),
    ("zero-weights-2", "loader: all objective weights zero", GII,
     ['objectives=[{"metric":"gii","weight":0},{"metric":"gdi","weight":0}]'], "validate", "refuse"),
    ("description-invalid-utf8", "runner: invalid UTF-8 from --set reaches result.json", GII,
     [b"description=bad \xff\xfe text"], "run", "any"),
    ("step-not-dividing-2", "loader: design step does not divide the range", GII, ["design.r.step=0.11"], "validate",
     "refuse"),
    ("scene-billions-planar", "scene: no size cap (billions of poses)", GII, ["scene.options.step=1e-9"], "validate",
     "refuse"),
    ("step-dividing-control", "control: a dividing step up to rounding", GII, ["design.l1.step=0.0145"], "validate",
     "accept"),
    ("threads-huge", "runner: no --threads cap / thread-creation failure", GII, ["threads=100000"], "run", "any"),
    ("name-absolute", "loader: study name used as a path", GII, ["name=@ABS@", "output={}"], "run-default-out", "contained"),
    ("steps-tiny-all", "loader: design grid size overflow", GII,
     ["design.l0.step=1e-9", "design.l1.step=1e-9", "design.l2.step=1e-9", "design.r.step=1e-9"], "validate", "refuse"),
    ("orientations-billions", "scene: no size cap (billions of poses)", ARM_PROBLEM, ["scene.options.orientations=2000000000"],
     "validate", "refuse"),
    ("box-tiny-step", "scene: no size cap (billions of poses)", "phantom3r-gii-box.json", ["scene.options.step=1e-7"],
     "validate", "refuse"),
    ("name-invalid-utf8", "runner: invalid UTF-8 from --set reaches result.json", GII, [b"name=caf\xe9"], "run", "any"),
    ("value-1e400", "loader: non-finite numbers", GII, ["scene.options.step=1e400"], "validate", "refuse"),
    ("index-huge", "loader: --set array index allocates", GII, ["objectives.100000000.weight=1"], "validate", "refuse"),
    ("seed-max-control", "control: the largest seed", GII, ["seed=18446744073709551615"], "run", "accept"),
    ("solver-plugin-path", "registry: plugin name used as a path", GII, ["solver.plugin=../grid"], "validate", "refuse"),
    ("step-negzero", "loader: step -0", GII, ["design.l1.step=-0"], "validate", "refuse"),
    ("joint3-billions", "scene: no size cap (billions of poses)", ARM_PROBLEM, ["scene.options.joint3_steps=2000000000"],
     "validate", "refuse"),
    ("disc-tiny-step", "scene: no size cap (billions of poses)", GII,
     ['scene={"plugin":"disc","options":{"radius":1,"step":1e-9}}'], "validate", "refuse"),
    ("index-4g", "loader: --set array index allocates", GII, ["objectives.4294967296.weight=1"], "validate", "refuse"),
]


def set_random_problems() -> list:
    return [GII, "fivebar-gii-culling-coarse.json", "fivebar-table2-best-gdi.json", "fivebar-pareto-nbi.json",
            "fivebar-gii-ga-coarse.json", "fivebar-pareto-sequential.json", "phantom3r-gii-box.json"]


def case_set(ctx: Ctx, case: Case, sb: Sandbox) -> Outcome:
    p = case.params
    sets = [s.replace("@ABS@", str(sb.root / "abs")) if isinstance(s, str) else s for s in p["sets"]]
    mode, expect = p["mode"], p["expect"]
    env = {}
    if mode == "validate-payload":
        d = sb.root / "plugins"
        (d / "hapsyn-y.so").mkdir(parents=True)
        shutil.copy(plugin_dir(ctx) / "hapsyn-fivebar.so", d / "payload.so")
        env["HAPSYN_PLUGIN_PATH"] = str(d)
    before = sb.snapshot()
    out = sb.cwd / "out"
    if mode.startswith("validate"):
        r = run(ctx, sb, ["validate", problem(p["problem"])] + with_sets(sets), env_extra=env)
        allowed = []
    elif mode == "run":
        r = run(ctx, sb, ["run", problem(p["problem"]), "--out", str(out), "--quiet"] + with_sets(sets), env_extra=env)
        allowed = [str(out)]
    else:  # run-default-out: the default output directory results/<name>
        r = run(ctx, sb, ["run", problem(p["problem"]), "--quiet"] + with_sets(sets), env_extra=env)
        allowed = [str(sb.cwd / "results")]
    cat, det = classify(r, "any" if expect == "contained" else expect)
    checks = [(cat, det)]
    after = sb.snapshot()
    temps = leftover_temps(before, after) if not r.timed_out and r.rc is not None and r.rc >= 0 else []
    if temps:
        checks.append(("mixed", "temporary files left: " + ", ".join(os.path.relpath(t, sb.root) for t in temps[:3])))
    bad = outside_writes(before, after, allowed)
    if bad:
        kind = "wrong" if expect == "contained" else "mixed"
        checks.append((kind, "wrote outside " + (allowed[0] if allowed else "(nothing allowed)") + ": " +
                       ", ".join(os.path.relpath(b, sb.root) for b in bad[:3])))
    if mode == "run" and r.rc is not None and r.rc >= 0 and not r.timed_out:
        probs = out_dir_problems(out, True)
        if probs:
            checks.append(("mixed", "; ".join(probs)))
        if r.rc == 0 and result_of(out) is None:
            checks.append(("wrong", "exit 0 without a readable result.json"))
    if case.kind == "seed-max-control" and r.rc == 0:
        doc = result_of(out) or {}
        if doc.get("seed") != 18446744073709551615:
            checks.append(("wrong", f"result.json seed {doc.get('seed')} != 18446744073709551615"))
    if case.kind == "threads-overflow" and r.rc == 0:
        doc = result_of(out) or {}
        checks.append(("wrong", f"threads=4294967297 ran with threads {doc.get('threads')}"))
    cat, det = worst(*checks)
    return outcome(r, cat, det)


def gen_set(seed: int, n: int) -> list:
    rng = random.Random(f"{seed}:set")
    cases = []
    for i in range(n):
        if i < len(SET_FIXED):
            kind, cause, prob, sets, mode, expect = SET_FIXED[i]
        else:
            prob = rng.choice(set_random_problems())
            doc = json.loads((PROBLEMS / prob).read_bytes())
            paths = [q for q in all_paths(doc) if q and q[0] not in ("description",)]
            q = rng.choice(paths)
            v = rng.choice(HOSTILE_VALUES)
            key = set_path_text(q).encode()
            sets = [key + b"=" + (v if isinstance(v, bytes) else v.encode())]
            kind, cause, mode, expect = "random", "set: hostile value on a real key", "validate", "any"
            if v in ("1e400", "-1e400", "NaN", "Infinity") and isinstance(get_at(doc, q), float):
                expect = "refuse"
        cases.append(Case("set", i, kind, cause, case_set,
                          {"problem": prob, "sets": sets, "mode": mode, "expect": expect}))
    return cases


# ------------------------------------------------------------------------------------------------
# Class cli: odd command lines.

def cli_fixed(sb: Sandbox) -> list:
    """kind, cause, argv builder (from the sandbox), expect, setup."""
    G = problem(GII)
    out = str(sb.cwd / "out")
    long_component = str(sb.cwd / ("n" * 300))
    long_path = str(sb.cwd / "/".join(["d" * 200] * 30))
    return [
        ("fifo-problem", "loader: problem file is a FIFO (blocks)", ["validate", str(sb.cwd / "fifo.json")], "refuse", "fifo"),
        ("dev-zero-problem", "loader: problem file is endless (/dev/zero)", ["validate", "/dev/zero"], "refuse", None),
        ("seed-minus-one", "runner: --seed -1 accepted", ["run", G, "--out", out, "--quiet", "--seed", "-1"], "refuse", None),
        ("threads-1000", "runner: no --threads cap", ["run", G, "--out", out, "--quiet", "--threads", "1000"], "any", None),
        ("out-long-component", "output: over-long path component", ["run", G, "--out", long_component, "--quiet"], "refuse", None),
        ("out-is-file", "output: --out is a file", ["run", G, "--out", str(sb.cwd / "file.txt"), "--quiet"], "refuse", "file"),
        ("out-dev-null", "output: --out /dev/null", ["run", G, "--out", "/dev/null", "--quiet"], "refuse", None),
        ("csv-onto-dir", "scene: --csv onto a directory", ["scene", G, "--csv", str(sb.cwd / "adir")], "refuse", "dir"),
        ("problem-is-dir", "loader: problem file is a directory", ["validate", str(sb.cwd / "adir")], "refuse", "dir"),
        ("problem-missing", "loader: missing problem file", ["validate", str(sb.cwd / "missing.json")], "refuse", None),
        ("out-invalid-utf8", "runner: invalid UTF-8 output path reaches result.json",
         ["run", G, "--out", os.fsencode(str(sb.cwd)) + b"/out\xff", "--quiet"], "any", None),
        ("huge-sparse-problem", "loader: huge problem file read whole", ["validate", str(sb.cwd / "huge.json")], "refuse", "huge"),
        ("threads-zero", "control: --threads 0 (all cores)", ["run", G, "--out", out, "--quiet", "--threads", "0"], "accept", None),
        ("threads-negative", "cli: --threads -1", ["run", G, "--out", out, "--quiet", "--threads", "-1"], "refuse", None),
        ("threads-4g", "cli: --threads beyond int", ["run", G, "--out", out, "--quiet", "--threads", "4294967297"], "refuse", None),
        ("out-long-path", "output: over-long path", ["run", G, "--out", long_path, "--quiet"], "refuse", None),
        ("empty-problem", "loader: empty problem file", ["validate", str(sb.cwd / "empty.json")], "refuse", "empty"),
        ("unknown-flag", "cli: unknown flag", ["run", G, "--bogus"], "refuse", None),
        ("set-no-equals", "loader: --set without '='", ["validate", G, "--set", "design.l1.step"], "refuse", None),
        ("set-empty-path", "loader: --set with an empty path", ["validate", G, "--set", "=1"], "refuse", None),
        ("set-index-negative", "loader: --set negative index", ["validate", G, "--set", "objectives.-1.weight=1"], "refuse", None),
        ("describe-path", "registry: plugin name used as a path", ["describe", "../../../../etc/passwd"], "refuse", None),
        ("describe-empty", "registry: empty plugin name", ["describe", ""], "refuse", None),
        ("seed-2-64", "cli: --seed beyond 64 bits", ["run", G, "--out", out, "--quiet", "--seed", "18446744073709551616"],
         "refuse", None),
        ("rerun-refused", "control: a finished study is not overwritten",
         ["run", G, "--out", out, "--quiet"], "refuse", "finished"),
        ("scene-plot-no-lattice", "scene: --plot without a lattice", ["scene", G, "--plot", str(sb.cwd / "plots")], "refuse", None),
        ("sweep-empty-values", "sweep: empty --vary values", ["sweep", G, "--vary", "scene.options.step=", "--out", out],
         "refuse", None),
        ("no-command", "cli: no subcommand", [], "refuse", None),
        ("resume-empty", "control: --resume on an empty directory", ["run", G, "--out", out, "--quiet", "--resume"], "any", None),
        ("problem-urandom", "loader: problem file is endless (/dev/urandom)", ["validate", "/dev/urandom"], "refuse", None),
    ]


CLI_FLAGS = ["--threads", "--seed", "--out", "--set", "--quiet", "--resume", "--force", "--csv", "--plot", "--vary",
             "--attribute", "--json", "--options", "--reference"]


def cli_setup(sb: Sandbox, setup: Optional[str]):
    if setup == "fifo":
        os.mkfifo(sb.cwd / "fifo.json")
    elif setup == "file":
        (sb.cwd / "file.txt").write_text("precious\n")
    elif setup == "dir":
        (sb.cwd / "adir").mkdir()
    elif setup == "huge":
        with open(sb.cwd / "huge.json", "wb") as f:
            f.truncate(3 * 1024 ** 3)  # sparse: 3 GiB of zero bytes
    elif setup == "empty":
        (sb.cwd / "empty.json").write_bytes(b"")


def case_cli(ctx: Ctx, case: Case, sb: Sandbox) -> Outcome:
    p = case.params
    if "fixed" in p:
        kind, cause, argv, expect, setup = cli_fixed(sb)[p["fixed"]]
        cli_setup(sb, setup)
        if setup == "finished":
            r0 = run(ctx, sb, ["run", problem(GII), "--out", str(sb.cwd / "out"), "--quiet"])
            if r0.rc != 0:
                return outcome(r0, *classify(r0))
    else:
        rng = random.Random(p["rng"])
        cmd = rng.choice(["run", "validate", "scene", "describe", "plugins", "sweep", "compare"])
        argv = [cmd]
        if cmd in ("run", "validate", "scene", "sweep", "compare"):
            argv.append(problem(rng.choice([GII, "fivebar-table2-best-gii.json", "fivebar-gii-culling-coarse.json"])))
        elif cmd == "describe":
            argv.append(rng.choice(["gii", "fivebar", "ga", "human_arm", "x" * 5000, "hapsyn-gii", "gii.so"]))
        for _ in range(rng.randint(1, 4)):
            flag = rng.choice(CLI_FLAGS)
            v = rng.choice(HOSTILE_VALUES[:24] + ["0", "2", "out", "scene.options.step=0.01"])
            argv += [flag, v] if flag not in ("--quiet", "--resume", "--force", "--json") else [flag]
        if cmd in ("run", "sweep", "compare") and "--out" not in argv:
            argv += ["--out", str(sb.cwd / "out")]
        if cmd == "run":
            argv.append("--quiet")
        expect = "any"
    before = sb.snapshot()
    r = run(ctx, sb, argv)
    checks = [classify(r, expect)]
    out = sb.cwd / "out"
    if out.is_dir() and not r.timed_out:
        probs = out_dir_problems(out, True)
        if probs:
            checks.append(("mixed", "; ".join(probs)))
    after = sb.snapshot()
    bad = outside_writes(before, after, [str(sb.cwd)])
    if bad:
        checks.append(("mixed", "wrote outside the working directory: " + ", ".join(bad[:3])))
    temps = leftover_temps(before, after) if not r.timed_out and r.rc is not None and r.rc >= 0 else []
    if temps:
        checks.append(("mixed", "temporary files left: " + ", ".join(os.path.relpath(t, sb.root) for t in temps[:3])))
    if case.kind == "out-is-file" and (sb.cwd / "file.txt").read_text() != "precious\n":
        checks.append(("wrong", "the file given as --out was overwritten"))
    cat, det = worst(*checks)
    return outcome(r, cat, det)


def gen_cli(seed: int, n: int) -> list:
    fixed = cli_fixed(_DummySb())
    cases = []
    for i in range(n):
        if i < len(fixed):
            cases.append(Case("cli", i, fixed[i][0], fixed[i][1], case_cli, {"fixed": i}))
        else:
            cases.append(Case("cli", i, "random", "cli: random odd arguments", case_cli, {"rng": f"{seed}:cli:{i}"}))
    return cases


class _DummySb:
    cwd = Path("/nonexistent")
    root = Path("/nonexistent")


# ------------------------------------------------------------------------------------------------
# Class output: kills, concurrent runs, run.log symlink, full filesystem.

def reference_run(ctx: Ctx, sets: list, key: str) -> dict:
    def make():
        sb = Sandbox(Path(tempfile.mkdtemp(prefix="ref-", dir=ctx.work)))
        out = sb.cwd / "out"
        r = run(ctx, sb, ["run", problem(OUT_PROBLEM), "--out", str(out), "--quiet"] + with_sets(sets), timeout=120)
        if r.rc != 0:
            raise RuntimeError(f"reference run failed ({r.rc}): {tail(r.err)}")
        return {"samples": sha(out / "samples.csv"), "maps": sha(out / "maps.csv"), "time": r.elapsed,
                "step": result_of(out)["problem"]["scene"]["options"]["step"], "dir": str(out)}
    return ctx.once(key, make)


def which_run(out: Path, refs: dict) -> dict:
    """Which reference run (A or B) each file of the directory belongs to."""
    state = {}
    doc = result_of(out)
    if (out / "result.json").exists():
        step = None
        try:
            step = doc["problem"]["scene"]["options"]["step"]
        except (TypeError, KeyError):
            pass
        state["result"] = next((k for k, v in refs.items() if v["step"] == step), "?")
    for f, key in (("samples.csv", "samples"), ("maps.csv", "maps")):
        if (out / f).exists():
            h = sha(out / f)
            state[f] = next((k for k, v in refs.items() if v[key] == h), "partial")
    return state


def state_problems(state: dict, earlier: str = "") -> list:
    """`earlier`: the run whose finished outputs a killed run was clearing. The contract (README,
    "The program"): result.json is the commit point; a run killed while it removes the earlier
    study (result.json first) may leave that study's other files with no result.json naming
    them, and the next run into the directory removes them. Anything else is mixed."""
    probs = []
    res = state.get("result")
    for f in ("samples.csv", "maps.csv"):
        if f in state:
            if res is None and state[f] == earlier and earlier:
                continue
            if res is None:
                probs.append(f"{f} of run {state[f]} without result.json")
            elif state[f] != res:
                probs.append(f"result.json of run {res} beside {f} of run {state[f]}")
    return probs


def case_output(ctx: Ctx, case: Case, sb: Sandbox) -> Outcome:
    kind = case.kind
    rng = random.Random(case.params["rng"])
    out = sb.cwd / "out"
    P = problem(OUT_PROBLEM)
    if kind in ("kill-random", "kill-after-samples"):
        refs = {"A": reference_run(ctx, OUT_A, "ref-A"), "B": reference_run(ctx, OUT_B, "ref-B")}
        shutil.copytree(refs["A"]["dir"], out)
        t0 = time.monotonic()
        p, cmd, argv = start(ctx, sb, ["run", P, "--out", str(out), "--quiet", "--force"] + with_sets(OUT_B))
        detail = ""
        if kind == "kill-random":
            delay = rng.uniform(0.0, 1.3 * refs["B"]["time"])
            detail = f"SIGKILL after {delay:.3f} s"
            while p.poll() is None and time.monotonic() - t0 < delay:
                time.sleep(0.002)
        else:
            ino = os.stat(out / "samples.csv").st_ino
            detail = "SIGKILL as soon as samples.csv was replaced"
            while p.poll() is None and time.monotonic() - t0 < 60:
                try:
                    if os.stat(out / "samples.csv").st_ino != ino:
                        break
                except OSError:
                    pass
                time.sleep(0.0005)
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
        else:
            detail += " (the run had already ended)"
        r = finish(p, cmd, argv, 60, t0)
        state = which_run(out, refs)
        probs = state_problems(state, "A")
        if probs:
            return outcome(r, "mixed", detail + ": " + "; ".join(probs))
        if "result" not in state and any(f in state for f in ("samples.csv", "maps.csv")):
            # Leftovers of run A: the next run must remove them before it writes anything.
            r2 = run(ctx, sb, ["run", P, "--out", str(out), "--quiet"] + with_sets(OUT_B))
            state2 = which_run(out, refs)
            probs = state_problems(state2)
            if r2.rc != 0 or probs or state2.get("result") != "B":
                return outcome(r2, "mixed", detail + f": the next run did not clear run A's leftovers: rc {r2.rc}, "
                               f"state {state2}; " + "; ".join(probs))
        if r.rc == 0 and state.get("result") != "B":
            return outcome(r, "wrong", detail + f": exit 0 but result.json is of run {state.get('result')}")
        return outcome(r, "ok", detail + f": state {state}")
    if kind in ("concurrent-empty", "concurrent-force"):
        refs = {"A": reference_run(ctx, OUT_A, "ref-A"), "B": reference_run(ctx, OUT_B, "ref-B")}
        extra = []
        if kind == "concurrent-force":
            shutil.copytree(refs["A"]["dir"], out)
            extra = ["--force"]
        t0 = time.monotonic()
        procs = [start(ctx, sb, ["run", P, "--out", str(out), "--quiet"] + extra + with_sets(OUT_B)) for _ in range(2)]
        rs = [finish(p, cmd, argv, ctx.args.timeout * 3, t0) for p, cmd, argv in procs]
        checks = [classify(r) for r in rs]
        ok_count = sum(1 for r in rs if r.rc == 0)
        if ok_count == 2:
            checks.append(("wrong", "both runs into one directory succeeded (exactly one may; no output lock)"))
        elif ok_count == 0 and all(not r.timed_out for r in rs):
            checks.append(("wrong", "neither run succeeded: " + first_error_line(rs[0].err)))
        probs = out_dir_problems(out, True) + state_problems(which_run(out, refs))
        if probs:
            checks.append(("mixed", "; ".join(probs)))
        cat, det = worst(*checks)
        return Outcome(cat, det, rs[0].cmd + "   # twice, at the same time", rs[0].rc, rs[0].elapsed,
                       tail(rs[0].err + "\n" + rs[1].err))
    if kind in ("runlog-symlink", "runlog-symlink-resume"):
        out.mkdir()
        victim = sb.root / "victim.txt"
        victim.write_text("precious\n")
        os.symlink(victim, out / "run.log")
        args = ["run", P, "--out", str(out), "--quiet"] + with_sets(OUT_A)
        if kind.endswith("resume"):
            args.append("--resume")
        r = run(ctx, sb, args)
        checks = [classify(r)]
        if victim.read_text() != "precious\n":
            checks.append(("wrong", f"run.log is a symlink and its target {victim.name} was written through it"))
        cat, det = worst(*checks)
        return outcome(r, cat, det)
    if kind in ("samples-is-dir", "result-is-dir"):
        out.mkdir()
        (out / ("samples.csv" if kind == "samples-is-dir" else "result.json")).mkdir()
        r = run(ctx, sb, ["run", P, "--out", str(out), "--quiet", "--force"] + with_sets(OUT_A))
        checks = [classify(r)]
        names = set(os.listdir(out))
        if kind == "samples-is-dir" and "result.json" in names and r.rc != 0:
            checks.append(("mixed", "failed run left a result.json"))
        if kind == "result-is-dir" and ({"maps.csv", "samples.csv"} & names):
            checks.append(("mixed", "CSVs written though result.json cannot be: " + ", ".join(sorted(names))))
        cat, det = worst(*checks)
        return outcome(r, cat, det)
    if kind in ("full-fs", "full-fs-prefilled", "full-fs-force", "full-fs-tight"):
        if not ctx.is_root:
            return Outcome("skip", "not root: cannot mount a tmpfs")
        mnt = sb.root / "fs"
        mnt.mkdir()
        # full-fs-force first writes a finished study, which needs the runner's 1 MiB floor free.
        size = "4m" if kind == "full-fs-force" else "200k"
        m = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(mnt)], capture_output=True, text=True)
        if m.returncode != 0:
            return Outcome("skip", "mount -t tmpfs failed: " + m.stderr.strip())
        try:
            fout = mnt / "out"
            if kind == "full-fs-prefilled":
                with open(mnt / "filler", "wb") as f:
                    try:
                        f.write(b"\0" * (400 * 1024))
                    except OSError:
                        pass
            args = ["run", P, "--out", str(fout), "--quiet", "--force"] + with_sets(OUT_A)
            if kind == "full-fs-tight":
                # A small study (CSVs of a few KiB) on a filesystem with 2, 4, ... 40 KiB left
                # (one run each, on a cleaned filesystem): some files fit, the later ones do not.
                args = ["run", P, "--out", str(fout), "--quiet", "--force", "--set", "scene.options.step=0.01"]
                sizes = list(range(2, 42, 2))
                rng.shuffle(sizes)
                r = None
                for kib in sizes:
                    shutil.rmtree(fout, ignore_errors=True)
                    (mnt / "filler").unlink(missing_ok=True)
                    st = os.statvfs(mnt)
                    with open(mnt / "filler", "wb") as f:
                        try:
                            f.write(b"\0" * max(0, st.f_bavail * st.f_frsize - kib * 1024))
                        except OSError:
                            pass
                    r = run(ctx, sb, args)
                    checks = [classify(r)]
                    probs = out_dir_problems(fout, True)
                    if probs:
                        checks.append(("mixed", f"{kib} KiB free: " + "; ".join(probs)))
                    cat, det = worst(*checks)
                    if cat != "ok":
                        break
                o = outcome(r, cat, det)
                o.cmd = f"mount -t tmpfs -o size=200k tmpfs {mnt} && (fill it up to {kib} KiB free) && " + o.cmd
                return o
            if kind == "full-fs-force":
                small = ["scene.options.step=0.01"]
                r0 = run(ctx, sb, ["run", P, "--out", str(fout), "--quiet"] + with_sets(small))
                if r0.rc != 0:
                    return outcome(r0, "skip", "could not write the first (small) study: " + first_error_line(r0.err))
                # Then the file system fills up (100 KiB left) before the --force run.
                st = os.statvfs(mnt)
                with open(mnt / "filler", "wb") as f:
                    try:
                        f.write(b"\0" * max(0, st.f_bavail * st.f_frsize - 100 * 1024))
                    except OSError:
                        pass
            r = run(ctx, sb, args)
            checks = [classify(r, "any" if kind == "full-fs-tight" else "refuse")]
            probs = out_dir_problems(fout, True)
            if probs:
                checks.append(("mixed", "; ".join(probs)))
            if kind == "full-fs-force" and r.rc != 0:
                doc = result_of(fout)
                if doc is None:
                    checks.append(("mixed", "the failed --force run destroyed the earlier finished result.json"))
            cat, det = worst(*checks)
            o = outcome(r, cat, det)
            o.cmd = f"mount -t tmpfs -o size={size} tmpfs {mnt} && " + o.cmd
            return o
        finally:
            subprocess.run(["umount", "-l", str(mnt)], capture_output=True)
    raise ValueError(kind)


OUTPUT_KINDS = [
    ("kill-after-samples", "runner: output files not staged (old result.json + new CSVs)"),
    ("concurrent-empty", "runner: no output lock (two runs into one directory)"),
    ("runlog-symlink", "runner: run.log followed as a symlink"),
    ("full-fs-tight", "runner: full filesystem leaves a partial output"),
    ("kill-random", "runner: output files not staged (old result.json + new CSVs)"),
    ("concurrent-force", "runner: no output lock (two runs into one directory)"),
    ("full-fs", "runner: full filesystem leaves a partial output"),
    ("runlog-symlink-resume", "runner: run.log followed as a symlink"),
    ("samples-is-dir", "runner: output path occupied by a directory"),
    ("result-is-dir", "runner: output path occupied by a directory"),
    ("full-fs-force", "runner: full filesystem leaves a partial output"),
    ("full-fs-prefilled", "runner: no free-space check"),
]


def gen_output(seed: int, n: int) -> list:
    cases = []
    for i in range(n):
        if i < len(OUTPUT_KINDS):
            kind, cause = OUTPUT_KINDS[i]
        elif i % 4 == 0:
            kind, cause = OUTPUT_KINDS[1]
        elif i % 4 == 1:
            kind, cause = OUTPUT_KINDS[3]
        else:
            kind, cause = OUTPUT_KINDS[4]
        cases.append(Case("output", i, kind, cause, case_output, {"rng": f"{seed}:output:{i}"}))
    return cases


# ------------------------------------------------------------------------------------------------
# Class checkpoint: damaged checkpoints with --resume.

def ga_checkpoint(ctx: Ctx, key: str, sets: list) -> bytes:
    def make():
        sb = Sandbox(Path(tempfile.mkdtemp(prefix="ckpt-", dir=ctx.work)))
        out = sb.cwd / "out"
        t0 = time.monotonic()
        p, cmd, argv = start(ctx, sb, ["run", problem(GA_PROBLEM), "--out", str(out), "--quiet"] + with_sets(sets))
        ck = out / "checkpoint.json"
        data = None
        while p.poll() is None and time.monotonic() - t0 < 120:
            if ck.exists():
                try:
                    data = ck.read_bytes()
                    json.loads(data)
                except (OSError, ValueError):
                    data = None
                if data:
                    break
            time.sleep(0.002)
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        if not data and ck.exists():
            data = ck.read_bytes()
        if not data:
            raise RuntimeError("the GA study wrote no checkpoint.json (" + cmd + ")")
        return data
    return ctx.once(key, make)


def edit_numbers(doc, key_re, value):
    n = 0
    if isinstance(doc, dict):
        for k, v in list(doc.items()):
            if re.search(key_re, k) and isinstance(v, (int, float)) and not isinstance(v, bool):
                doc[k] = value
                n += 1
            else:
                n += edit_numbers(v, key_re, value)
    elif isinstance(doc, list):
        for v in doc:
            n += edit_numbers(v, key_re, value)
    return n


def fnv1a_hex(text: bytes) -> str:
    h = 1469598103934665603
    for c in text:
        h ^= c
        h = (h * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return "%x" % h


CHECKPOINT_KINDS = [
    ("truncated", "checkpoint: damaged file accepted", "refuse"),
    ("edited-score", "checkpoint: edited file accepted", "refuse"),
    ("other-study", "checkpoint: another study's file accepted", "refuse"),
    ("fifo", "checkpoint: FIFO blocks", "refuse"),
    ("pristine", "control: resume from a valid checkpoint", "accept"),
    ("edited-score-rechecksummed", "checkpoint: edited state trusted (score 99)", "any"),
    ("empty", "checkpoint: damaged file accepted", "refuse"),
    ("directory", "checkpoint: path is a directory", "refuse"),
    ("dev-zero", "checkpoint: endless file", "refuse"),
    ("garbage", "checkpoint: damaged file accepted", "refuse"),
    ("flip", "checkpoint: damaged file accepted", "refuse"),
    ("deep", "checkpoint: deep nesting", "refuse"),
    ("other-seed", "checkpoint: another seed", "refuse"),
    ("object", "checkpoint: damaged file accepted", "refuse"),
]


def case_checkpoint(ctx: Ctx, case: Case, sb: Sandbox) -> Outcome:
    rng = random.Random(case.params["rng"])
    expect = case.params["expect"]
    kind = case.kind
    good = ga_checkpoint(ctx, "ga-ckpt", GA_SETS)
    out = sb.cwd / "out"
    out.mkdir()
    ck = out / "checkpoint.json"
    extra = []
    if kind == "truncated":
        ck.write_bytes(good[: rng.randrange(1, len(good) - 2)])
    elif kind == "edited-score" or kind == "edited-score-rechecksummed":
        doc = json.loads(good)
        n = edit_numbers(doc.get("state", doc), r"score", 99.0)
        if n == 0:
            return Outcome("skip", "no score field found in the checkpoint")
        if kind.endswith("rechecksummed") and "checksum" in doc:
            doc.pop("checksum", None)
            doc["checksum"] = fnv1a_hex(json.dumps(doc, sort_keys=True, separators=(",", ":"), ensure_ascii=False).encode())
        ck.write_text(json.dumps(doc))
    elif kind == "other-study":
        ck.write_bytes(ga_checkpoint(ctx, "ga-ckpt-other", GA_SETS + ["design.l0.upper=0.2"]))
    elif kind == "fifo":
        os.mkfifo(ck)
    elif kind == "pristine":
        ck.write_bytes(good)
    elif kind == "empty":
        ck.write_bytes(b"")
    elif kind == "directory":
        ck.mkdir()
    elif kind == "dev-zero":
        os.symlink("/dev/zero", ck)
    elif kind == "garbage":
        ck.write_bytes(bytes(rng.randrange(256) for _ in range(len(good))))
    elif kind == "flip":
        b = bytearray(good)
        i = rng.randrange(len(b))
        b[i] = ord("7") if b[i] != ord("7") else ord("3")
        ck.write_bytes(bytes(b))
    elif kind == "deep":
        ck.write_bytes(b'{"format":"hapsyn-checkpoint","state":' + deep(100000, "array") + b"}")
    elif kind == "other-seed":
        ck.write_bytes(good)
        extra = ["--seed", "7"]
    elif kind == "object":
        ck.write_bytes(b"{}")
    r = run(ctx, sb, ["run", problem(GA_PROBLEM), "--out", str(out), "--quiet", "--resume"] + extra + with_sets(GA_SETS),
            timeout=max(ctx.args.timeout, 30))
    checks = [classify(r, expect)]
    if expect == "refuse" and r.rc == 1 and "checkpoint.json" not in r.err:
        checks.append(("wrong", "refused, but the message does not name checkpoint.json: " + first_error_line(r.err)))
    if r.rc == 0:
        doc = result_of(out) or {}
        best = (doc.get("best") or {}).get("objectives", {})
        gii, score = best.get("gii"), (doc.get("best") or {}).get("score")
        if not isinstance(gii, (int, float)) or gii > 1.0 or gii < 0:
            checks.append(("wrong", f"resumed result has gii {gii} (must lie in [0, 1])"))
        if not isinstance(score, (int, float)) or score > 1.0:
            checks.append(("wrong", f"resumed result has best score {score} (GII: at most 1)"))
    if not r.timed_out:
        probs = out_dir_problems(out, True)
        if probs:
            checks.append(("mixed", "; ".join(probs)))
    cat, det = worst(*checks)
    return outcome(r, cat, det)


def gen_checkpoint(seed: int, n: int) -> list:
    cases = []
    for i in range(n):
        kind, cause, expect = CHECKPOINT_KINDS[i % len(CHECKPOINT_KINDS)]
        cases.append(Case("checkpoint", i, kind, cause, case_checkpoint, {"rng": f"{seed}:checkpoint:{i}", "expect": expect}))
    return cases


# ------------------------------------------------------------------------------------------------
# Class cache: damaged human_arm caches.

def arm_pristine(ctx: Ctx) -> dict:
    def make():
        sb = Sandbox(Path(tempfile.mkdtemp(prefix="arm-", dir=ctx.work)))
        cdir = sb.root / "cache"
        r = run(ctx, sb, ["scene", problem(ARM_PROBLEM), "--csv", str(sb.cwd / "scene.csv"), "--set",
                          f"scene.options.cache_directory={cdir}"] + with_sets(ARM_SETS), timeout=120)
        if r.rc != 0:
            raise RuntimeError(f"pristine human_arm scene failed ({r.rc}): {tail(r.err)}")
        files = sorted(cdir.glob("human_arm-*.bin"))
        if not files:
            raise RuntimeError("no human_arm-*.bin written into " + str(cdir))
        return {"csv": sha(sb.cwd / "scene.csv"), "cache": files[0].read_bytes(), "name": files[0].name}
    return ctx.once("arm", make)


CACHE_KINDS = ["truncated", "flip-payload", "flip-header", "fifo", "directory", "empty", "dev-zero", "garbage",
               "dir-is-file", "dir-is-fifo", "symlink-loop", "other-key", "truncated-10", "sparse-huge"]


def case_cache(ctx: Ctx, case: Case, sb: Sandbox) -> Outcome:
    rng = random.Random(case.params["rng"])
    ref = arm_pristine(ctx)
    kind = case.kind
    cdir = sb.root / "cache"
    cdir.mkdir()
    f = cdir / ref["name"]
    good = ref["cache"]
    if kind == "truncated":
        f.write_bytes(good[: rng.randrange(1, len(good) - 1)])
    elif kind == "truncated-10":
        f.write_bytes(good[:10])
    elif kind in ("flip-payload", "flip-header"):
        b = bytearray(good)
        lo, hi = (len(b) // 2, len(b)) if kind == "flip-payload" else (0, min(64, len(b)))
        for _ in range(rng.randint(1, 4)):
            i = rng.randrange(lo, hi)
            b[i] ^= 1 << rng.randrange(8)
        f.write_bytes(bytes(b))
    elif kind == "fifo":
        os.mkfifo(f)
    elif kind == "directory":
        f.mkdir()
    elif kind == "empty":
        f.write_bytes(b"")
    elif kind == "dev-zero":
        os.symlink("/dev/zero", f)
    elif kind == "garbage":
        f.write_bytes(bytes(rng.randrange(256) for _ in range(len(good))))
    elif kind == "dir-is-file":
        shutil.rmtree(cdir)
        cdir.write_text("not a directory\n")
    elif kind == "dir-is-fifo":
        shutil.rmtree(cdir)
        os.mkfifo(cdir)
    elif kind == "symlink-loop":
        os.symlink(f.name, f)
    elif kind == "other-key":
        other = arm_other(ctx)
        f.write_bytes(other)
    elif kind == "sparse-huge":
        with open(f, "wb") as h:
            h.write(good[:64])
            h.truncate(8 * 1024 ** 3)
    csv = sb.cwd / "scene.csv"
    r = run(ctx, sb, ["scene", problem(ARM_PROBLEM), "--csv", str(csv), "--set", f"scene.options.cache_directory={cdir}"]
            + with_sets(ARM_SETS))
    checks = [classify(r)]
    if r.rc == 0 and sha(csv) != ref["csv"]:
        checks.append(("wrong", "the scene differs from the pristine build (the damaged cache was trusted)"))
    cat, det = worst(*checks)
    if cat == "ok":
        m = re.search(r"cache_status: (.*)", r.out)
        det = (det + "; " if det else "") + ("cache_status: " + m.group(1)[:160] if m else "")
    return outcome(r, cat, det)


def arm_other(ctx: Ctx) -> bytes:
    def make():
        sb = Sandbox(Path(tempfile.mkdtemp(prefix="arm2-", dir=ctx.work)))
        cdir = sb.root / "cache"
        sets = [s.replace("orientations=7", "orientations=9") for s in ARM_SETS]
        r = run(ctx, sb, ["scene", problem(ARM_PROBLEM), "--set", f"scene.options.cache_directory={cdir}"] + with_sets(sets),
                timeout=120)
        files = sorted(cdir.glob("human_arm-*.bin"))
        if r.rc != 0 or not files:
            raise RuntimeError("second human_arm scene failed: " + tail(r.err))
        return files[0].read_bytes()
    return ctx.once("arm-other", make)


def gen_cache(seed: int, n: int) -> list:
    return [Case("cache", i, CACHE_KINDS[i % len(CACHE_KINDS)], "scene cache: " + CACHE_KINDS[i % len(CACHE_KINDS)],
                 case_cache, {"rng": f"{seed}:cache:{i}"}) for i in range(n)]


# ------------------------------------------------------------------------------------------------
# Class plugins: damaged plugin files on HAPSYN_PLUGIN_PATH.

def plugin_dir(ctx: Ctx) -> Path:
    def make():
        cands = [Path(ctx.hapsyn).parent.parent / "lib" / "hapsyn" / "plugins"]
        for c in cands:
            if (c / "hapsyn-fivebar.so").exists():
                return c
        r = subprocess.run([ctx.hapsyn, "plugins"], capture_output=True, text=True, env=ctx.env, timeout=60)
        m = re.search(r"(\S+)/hapsyn-fivebar\.so", r.stdout)
        if not m:
            raise RuntimeError("cannot find the plugin directory: " + r.stdout[-300:])
        return Path(m.group(1))
    return ctx.once("plugin-dir", make)


PLUGIN_KINDS = ["truncated", "truncated-header", "fifo", "empty", "directory", "text", "dev-zero", "symlink-loop",
                "renamed-copy", "truncated", "elf-garbage", "truncated"]


def case_plugins(ctx: Ctx, case: Case, sb: Sandbox) -> Outcome:
    rng = random.Random(case.params["rng"])
    kind = case.kind
    src_dir = plugin_dir(ctx)
    d = sb.root / "plugins"
    d.mkdir()
    victim = rng.choice(["gii", "gdi", "fivebar", "planar_square", "grid"])
    so = (src_dir / f"hapsyn-{victim}.so").read_bytes()
    f = d / f"hapsyn-{victim}.so"
    what = ""
    if kind == "truncated":
        n = rng.randrange(64, len(so) - 1)
        f.write_bytes(so[:n])
        what = f"hapsyn-{victim}.so truncated to {n} of {len(so)} bytes"
    elif kind == "truncated-header":
        f.write_bytes(so[:rng.choice([4, 16, 52, 64, 200])])
        what = f"hapsyn-{victim}.so cut inside the ELF header"
    elif kind == "fifo":
        os.mkfifo(f)
        what = f"hapsyn-{victim}.so is a FIFO"
    elif kind == "empty":
        f.write_bytes(b"")
        what = "empty .so"
    elif kind == "directory":
        f.mkdir()
        what = ".so is a directory"
    elif kind == "text":
        f.write_text("not a shared library\n")
        what = ".so is a text file"
    elif kind == "dev-zero":
        os.symlink("/dev/zero", f)
        what = ".so is a symlink to /dev/zero"
    elif kind == "symlink-loop":
        os.symlink(f.name, f)
        what = ".so is a symlink to itself"
    elif kind == "renamed-copy":
        (d / "hapsyn-other.so").write_bytes(so)
        what = f"a copy of hapsyn-{victim}.so named hapsyn-other.so"
    elif kind == "elf-garbage":
        f.write_bytes(so[:64] + bytes(rng.randrange(256) for _ in range(4096)))
        what = "ELF header followed by garbage"
    env = {"HAPSYN_PLUGIN_PATH": str(d)}
    checks = []
    r = None
    for argv in (["plugins"], ["validate", problem(GII)], ["describe", victim]):
        r = run(ctx, sb, argv, env_extra=env)
        cat, det = classify(r)
        if cat != "ok":
            checks.append((cat, f"{argv[0]}: {det}"))
            break
    cat, det = worst(*(checks or [("ok", "")]))
    return outcome(r, cat, what + (": " + det if det else ""))


def gen_plugins(seed: int, n: int) -> list:
    return [Case("plugins", i, PLUGIN_KINDS[i % len(PLUGIN_KINDS)],
                 "registry: damaged plugin file (" + PLUGIN_KINDS[i % len(PLUGIN_KINDS)] + ")", case_plugins,
                 {"rng": f"{seed}:plugins:{i}"}) for i in range(n)]


# ------------------------------------------------------------------------------------------------
# Class signal: a stop request to a running long study.

SIGNAL_STUDIES = [
    ("ga", GA_PROBLEM, ["solver.options.generations=1000000", "solver.options.stall_generations=1000000",
                        "solver.options.ftol=0", "solver.options.checkpoint_every=5"]),
    ("grid", GII, ["solver.options.prune=false", "design.l0.step=0.005", "design.l1.step=0.005", "design.l2.step=0.005",
                   "design.r.step=0.005"]),
    # Without block bounds: with them the study ends in about 2 s, and a signal 1 to 3.5 s after
    # the start lands in its outputs or after it, depending on the machine's load.
    ("culling", "fivebar-gii-culling-paper.json", ["solver.options.block_bounds=false"]),
    ("nsga2", "fivebar-pareto-nsga2.json", ["solver.options.generations=1000000"]),
    ("weighted_sum", "fivebar-pareto-weighted-sum.json", ["solver.options.count=200"]),
]
SIGNAL_KINDS = ["sigint", "double-sigint", "sigterm", "sigusr1"]


def case_signal(ctx: Ctx, case: Case, sb: Sandbox) -> Outcome:
    rng = random.Random(case.params["rng"])
    solver, prob, sets = SIGNAL_STUDIES[case.params["study"]]
    kind = case.kind
    bound = ctx.args.stop_bound
    out = sb.cwd / "out"
    t0 = time.monotonic()
    p, cmd, argv = start(ctx, sb, ["run", problem(prob), "--out", str(out), "--threads", "2"] + with_sets(sets))
    # Wait until the solver has started (run.log written), then a little more.
    while p.poll() is None and not (out / "run.log").exists() and time.monotonic() - t0 < 60:
        time.sleep(0.01)
    delay = rng.uniform(1.0, 3.0)
    while p.poll() is None and time.monotonic() - t0 < delay + 0.5:
        time.sleep(0.01)
    if p.poll() is not None:
        r = finish(p, cmd, argv, 10, t0)
        return outcome(r, "skip" if r.rc == 0 else classify(r)[0], "the study ended before the signal: " + first_error_line(r.err))
    sig = {"sigint": signal.SIGINT, "double-sigint": signal.SIGINT, "sigterm": signal.SIGTERM,
           "sigusr1": signal.SIGUSR1}[kind]
    ts = time.monotonic()
    os.kill(p.pid, sig)
    if kind == "double-sigint":
        time.sleep(0.3)
        if p.poll() is None:
            os.kill(p.pid, signal.SIGINT)
        ts2 = time.monotonic()
        r = finish(p, cmd, argv, 15, ts2)
        took = time.monotonic() - ts2
        checks = []
        if r.timed_out or took > 5:
            checks.append(("hang", f"second SIGINT: still running {took:.1f} s later"))
        elif r.rc not in (0, EXIT_STOPPED, 130, -2):
            checks.append(classify(r))
        probs = out_dir_problems(out, False)
        if probs:
            checks.append(("mixed", "; ".join(probs)))
        cat, det = worst(*(checks or [("ok", f"ended {took:.2f} s after the second SIGINT, exit {r.rc}")]))
        o = outcome(r, cat, f"{solver}: {det}")
        o.cmd = cmd + f"   # then kill -INT twice after {delay:.1f} s"
        return o
    r = finish(p, cmd, argv, bound + 10, ts)
    took = time.monotonic() - ts
    checks = []
    if r.timed_out or took > bound:
        checks.append(("hang", f"{sig.name}: still running {took:.1f} s later (bound {bound:.0f} s)"))
    else:
        doc = result_of(out)
        if r.rc != EXIT_STOPPED:
            checks.append(classify(r, "accept"))
            if r.rc == 0:
                checks.append(("wrong", f"exit 0 after {sig.name}: a stopped run exits {EXIT_STOPPED}"))
        else:
            if doc is None:
                checks.append(("wrong", "exit 0 without result.json"))
            elif doc.get("status") != "stopped":
                checks.append(("wrong", f"result.json status {doc.get('status')!r}, not 'stopped'"))
            if not (out / "checkpoint.json").exists():
                checks.append(("wrong", "no checkpoint.json after a stop"))
        probs = out_dir_problems(out, True)
        if probs:
            checks.append(("mixed", "; ".join(probs)))
        if r.rc == EXIT_STOPPED and doc is not None and doc.get("status") == "stopped":
            checks.append(resume_after_stop(ctx, sb, prob, sets, out))
    cat, det = worst(*checks)
    o = outcome(r, cat, f"{solver}: " + (det or f"stopped {took:.1f} s after {sig.name}"))
    o.cmd = cmd + f"   # then kill -{sig.name[3:]} after {delay:.1f} s"
    return o


def resume_after_stop(ctx: Ctx, sb: Sandbox, prob: str, sets: list, out: Path) -> tuple:
    """A stopped study continues with --resume: it must start (not be refused as finished) and
    stop again on SIGINT."""
    t0 = time.monotonic()
    p, cmd, argv = start(ctx, sb, ["run", problem(prob), "--out", str(out), "--threads", "2", "--resume"] + with_sets(sets))
    while p.poll() is None and time.monotonic() - t0 < 3.0:
        time.sleep(0.02)
    if p.poll() is None:
        os.kill(p.pid, signal.SIGINT)
    r = finish(p, cmd, argv, ctx.args.stop_bound + 10, t0)
    if r.timed_out:
        return "hang", "the resumed run did not stop on SIGINT"
    if r.rc == 1 and "finished" in r.err:
        return "wrong", "a stopped study cannot be resumed (--resume refuses it as finished): " + first_error_line(r.err)
    if r.rc == EXIT_STOPPED:
        return "ok", ""
    cat, det = classify(r, "accept")
    return cat, ("--resume after the stop: " + det) if det else ""


def gen_signal(seed: int, n: int) -> list:
    cases = []
    for i in range(n):
        study = i % len(SIGNAL_STUDIES)
        kind = "sigint" if i < len(SIGNAL_STUDIES) else SIGNAL_KINDS[1 + (i - len(SIGNAL_STUDIES)) % 3]
        solver = SIGNAL_STUDIES[study][0]
        cause = f"solver {solver}: no graceful stop with a checkpoint" if kind != "double-sigint" else "runner: second signal"
        cases.append(Case("signal", i, kind, cause, case_signal, {"rng": f"{seed}:signal:{i}", "study": study}))
    return cases


GENERATORS = {"json": gen_json, "set": gen_set, "cli": gen_cli, "output": gen_output, "checkpoint": gen_checkpoint,
              "cache": gen_cache, "plugins": gen_plugins, "signal": gen_signal}

# The file surfaces and the Python module (surfaces.py): it takes this module's helpers as an argument.
sys.path.insert(0, str(Path(__file__).resolve().parent))
import surfaces  # noqa: E402
CLASSES[-1:-1] = surfaces.CLASSES
GENERATORS.update(surfaces.generators(sys.modules[__name__]))


# ------------------------------------------------------------------------------------------------
# The campaign.

def run_case(ctx: Ctx, case: Case) -> Outcome:
    root = ctx.work / "cases" / case.cid
    if root.exists():
        shutil.rmtree(root, ignore_errors=True)
    sb = Sandbox(root)
    t0 = time.monotonic()
    try:
        o = case.fn(ctx, case, sb)
    except SetupError as e:
        o = Outcome("skip", str(e))
    except Exception as e:  # noqa: BLE001 - a bug of this script must not end the campaign
        o = Outcome("skip", f"attack.py error: {type(e).__name__}: {e}")
    o.elapsed = o.elapsed or (time.monotonic() - t0)
    if o.category in ("ok", "skip") and not ctx.args.keep:
        subprocess.run(["umount", "-l", str(root / "fs")], capture_output=True) if (root / "fs").is_mount() else None
        shutil.rmtree(root, ignore_errors=True)
    return o


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hapsyn", default=str(ROOT / "build" / "bin" / "hapsyn"), help="the hapsyn binary")
    ap.add_argument("--classes", default=",".join(CLASSES), help="comma-separated classes (default: all)")
    ap.add_argument("--per-class", type=int, default=10, help="inputs per class (default 10)")
    ap.add_argument("--n", action="append", default=[], metavar="CLASS=N", help="inputs for one class (repeatable)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=20.0, help="seconds before a run counts as a hang (default 20)")
    ap.add_argument("--stop-bound", type=float, default=20.0, help="seconds a stop request may take (default 20)")
    ap.add_argument("--mem-mb", type=int, default=4096, help="address-space limit of every hapsyn run (0: none)")
    ap.add_argument("--work", default="", help="work directory (default: a new temporary directory)")
    ap.add_argument("--keep", action="store_true", help="keep the sandboxes of passing cases too")
    ap.add_argument("--only", default="", help="run only these case ids (comma-separated, e.g. json-0003,set-0001)")
    ap.add_argument("--json", default="", help="write the table and every case here")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    args = ap.parse_args(argv)

    if not os.access(args.hapsyn, os.X_OK):
        print(f"attack.py: {args.hapsyn} is not an executable (build first, or pass --hapsyn)", file=sys.stderr)
        return 2
    classes = [c for c in args.classes.split(",") if c]
    for c in classes:
        if c not in GENERATORS:
            print(f"attack.py: unknown class {c!r}; known: {', '.join(CLASSES)}", file=sys.stderr)
            return 2
    counts = {c: args.per_class for c in classes}
    for item in args.n:
        c, _, v = item.partition("=")
        counts[c] = int(v)
    cases = [case for c in classes for case in GENERATORS[c](args.seed, counts.get(c, args.per_class))]
    if args.only:
        wanted = set(args.only.split(","))
        cases = [c for c in cases if c.cid in wanted]
    if args.list:
        for c in cases:
            print(f"{c.cid:18} {c.kind:28} {c.cause}")
        return 0
    args.work = args.work or tempfile.mkdtemp(prefix="hapsyn-attack-")
    work = Path(args.work)
    if work.exists() and any(work.iterdir()):
        if not (work / ".hapsyn-attack").exists():
            print(f"attack.py: --work {work} is not empty and not an attack work directory", file=sys.stderr)
            return 2
        for m in sorted(work.glob("cases/*/fs")):
            subprocess.run(["umount", "-l", str(m)], capture_output=True)
        shutil.rmtree(work)
    work.mkdir(parents=True, exist_ok=True)
    (work / ".hapsyn-attack").write_text("a work directory of tests/attack/attack.py: deleted at the next campaign\n")
    ctx = Ctx(args)
    print(f"attack: {len(cases)} cases, seed {args.seed}, {args.jobs} jobs, hapsyn {ctx.hapsyn}, work {ctx.work}",
          flush=True)

    # Signal cases need the CPU for their time bound: they run last, one at a time.
    timed = [c for c in cases if c.cls == "signal"]
    rest = [c for c in cases if c.cls != "signal"]
    results = {}
    t_start = time.monotonic()

    def record(case, o):
        results[case.cid] = o
        mark = "." if o.category == "ok" else ("s" if o.category == "skip" else "!")
        if o.category not in ("ok", "skip"):
            print(f"\n  {case.cid} {o.category}: {o.detail[:200]}", flush=True)
        else:
            print(mark, end="", flush=True)

    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        futs = {pool.submit(run_case, ctx, c): c for c in rest}
        for f in concurrent.futures.as_completed(futs):
            record(futs[f], f.result())
    for c in timed:
        record(c, run_case(ctx, c))
    print(f"\nattack: done in {time.monotonic() - t_start:.0f} s", flush=True)

    table = {}
    for c in cases:
        row = table.setdefault(c.cls, {k: 0 for k in ["tried"] + CATEGORIES + ["skip"]})
        row["tried"] += 1
        row[results[c.cid].category] += 1
    total = {k: sum(r[k] for r in table.values()) for k in ["tried"] + CATEGORIES + ["skip"]}
    cols = ["tried"] + CATEGORIES + ["skip"]
    print("\n" + f"{'class':12}" + "".join(f"{k:>9}" for k in cols))
    for cls in classes:
        if cls in table:
            print(f"{cls:12}" + "".join(f"{table[cls][k]:>9}" for k in cols))
    print(f"{'total':12}" + "".join(f"{total[k]:>9}" for k in cols))

    failing = [c for c in cases if results[c.cid].category not in ("ok", "skip")]
    me = [sys.executable, str(Path(__file__).resolve()), "--hapsyn", ctx.hapsyn, "--seed", str(args.seed)]
    if failing:
        print(f"\nfailing cases ({len(failing)}):")
        for c in failing:
            o = results[c.cid]
            print(f"  [{c.cid}] {o.category} ({c.kind}): {o.detail[:300]}")
            print(f"      run:   {o.cmd[:700]}")
            print(f"      again: {shline(me + ['--only', c.cid, '--n', f'{c.cls}={counts[c.cls]}', '--classes', c.cls])}")
        by_cause = {}
        for c in failing:
            by_cause.setdefault(c.cause, []).append(c)
        print(f"\nfailures by cause ({len(by_cause)}):")
        for cause, cs in sorted(by_cause.items(), key=lambda kv: (-len(kv[1]), kv[0])):
            cats = sorted({results[c.cid].category for c in cs})
            print(f"  {len(cs):3} x {cause} [{'/'.join(cats)}]: e.g. {cs[0].cid}")
    skipped = [c for c in cases if results[c.cid].category == "skip"]
    for c in skipped:
        print(f"  skipped [{c.cid}] {results[c.cid].detail[:200]}")

    if args.json:
        doc = {"seed": args.seed, "hapsyn": ctx.hapsyn, "per_class": counts, "work": str(ctx.work),
               "table": table, "total": total,
               "cases": [dict(id=c.cid, cls=c.cls, kind=c.kind, cause=c.cause,
                              again=shline(me + ['--only', c.cid, '--n', f'{c.cls}={counts[c.cls]}', '--classes', c.cls]),
                              **dataclasses.asdict(results[c.cid])) for c in cases]}
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(doc, indent=1) + "\n")
        print(f"written: {args.json}")
    return 1 if failing else 0


if __name__ == "__main__":
    sys.exit(main())
