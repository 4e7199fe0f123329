#!/usr/bin/env bash
# The "write your own metric plugin" path, end to end against the *installed* package:
#   1. install the build tree into a temporary prefix;
#   2. the installed hapsyn alone finds its installed built-in plugins;
#   3. configure and build examples/mean_isotropy with find_package(hapsyn) from that prefix;
#   4. the installed hapsyn lists and describes the new plugin, and runs the example study.
# Usage: out_of_tree_test.sh <hapsyn build dir> <hapsyn source dir>
# Uses nothing but the build tree and a temporary directory (removed on exit).
set -euo pipefail

if [[ $# -ne 2 ]]; then
  echo "usage: $0 <build dir> <source dir>" >&2
  exit 2
fi
build_dir=$(cd "$1" && pwd)
source_dir=$(cd "$2" && pwd)
example="$source_dir/examples/mean_isotropy"

tmp=$(mktemp -d "${TMPDIR:-/tmp}/hapsyn-oot.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

passed=0
failed=0
step() { echo "--- $*"; }
fail() {
  echo "FAIL: $*" >&2
  failed=$((failed + 1))
  echo "out-of-tree plugin: $passed passed, $failed failed"
  exit 1
}

prefix="$tmp/prefix"
hapsyn="$prefix/bin/hapsyn"

step "install $build_dir into $prefix"
cmake --install "$build_dir" --prefix "$prefix" >"$tmp/install.log" || { cat "$tmp/install.log"; fail "cmake --install"; }
for f in bin/hapsyn include/hapsyn/plugin.hpp include/hapsyn/metric.hpp \
         lib/cmake/hapsyn/hapsynConfig.cmake lib/cmake/hapsyn/hapsynConfigVersion.cmake \
         lib/cmake/hapsyn/hapsynTargets.cmake lib/cmake/hapsyn/HapsynPlugin.cmake \
         lib/cmake/hapsyn/embed_schema.cmake lib/hapsyn/plugins/hapsyn-fivebar.so; do
  [[ -e "$prefix/$f" ]] || fail "the install tree lacks $f"
done
ls "$prefix"/lib/libhapsyn.so* >/dev/null 2>&1 || fail "the install tree lacks lib/libhapsyn.so"

step "the installed binary resolves the installed libhapsyn"
ldd_out=$(ldd "$hapsyn") || fail "ldd $hapsyn"
grep -q "libhapsyn.*=> $prefix/" <<<"$ldd_out" || { echo "$ldd_out"; fail "ldd: $hapsyn does not use $prefix/lib/libhapsyn"; }
if grep -q "not found" <<<"$ldd_out"; then echo "$ldd_out"; fail "ldd: unresolved libraries"; fi

step "the installed hapsyn alone finds the installed built-in plugins"
builtin=$(env -u HAPSYN_PLUGIN_PATH "$hapsyn" plugins) || fail "hapsyn plugins (no HAPSYN_PLUGIN_PATH)"
echo "$builtin"
grep -Eq "^fivebar +mechanism .*$prefix/lib/hapsyn/plugins/hapsyn-fivebar\.so" <<<"$builtin" ||
  fail "'hapsyn plugins' does not list the installed fivebar"

step "configure and build $example against $prefix"
cmake -S "$example" -B "$tmp/build" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release \
  >"$tmp/configure.log" 2>&1 || { cat "$tmp/configure.log"; fail "configuring the example"; }
cmake --build "$tmp/build" >"$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; fail "building the example"; }
[[ -f "$tmp/build/plugins/hapsyn-mean_isotropy.so" ]] || fail "no $tmp/build/plugins/hapsyn-mean_isotropy.so"
if grep -q "warning:" "$tmp/build.log"; then cat "$tmp/build.log"; fail "the example compiles with warnings"; fi

export HAPSYN_PLUGIN_PATH="$tmp/build/plugins"

step "hapsyn plugins / describe"
listing=$("$hapsyn" plugins) || fail "hapsyn plugins"
echo "$listing"
grep -Eq "^mean_isotropy +metric .*$tmp/build/plugins/hapsyn-mean_isotropy\.so" <<<"$listing" || fail "'hapsyn plugins' does not list mean_isotropy"
grep -Eq "^fivebar +mechanism " <<<"$listing" || fail "'hapsyn plugins' lost the built-in plugins"
description=$("$hapsyn" describe mean_isotropy) || fail "hapsyn describe mean_isotropy"
echo "$description"
grep -Eq "^ +exponent +number +default 1 .*\[>= 0.1\]" <<<"$description" ||
  fail "'hapsyn describe mean_isotropy' does not show the exponent option"

step "hapsyn run examples/mean_isotropy/study.json"
"$hapsyn" run "$example/study.json" --out "$tmp/out" --quiet || fail "hapsyn run exited with $?"
python3 -c '
import json, sys
with open(sys.argv[1]) as f:
    r = json.load(f)
assert r["status"] == "converged", "status = %r: %s" % (r["status"], r.get("message"))
o = r["best"]["objectives"]
m, g = o["mean_isotropy"], o["gii"]
print("mean_isotropy = %.6f, gii = %.6f, samples = %d" % (m, g, r["samples_in_scene"]))
assert 0.0 < m <= 1.0, "mean_isotropy = %r is not in (0, 1]" % m
assert 0.0 < g <= 1.0, "gii = %r is not in (0, 1]" % g
assert m >= g, "mean_isotropy = %r < gii = %r" % (m, g)
files = [p["file"] for p in r["plugins"] if p["name"] == "mean_isotropy"]
assert files and files[0].endswith("/plugins/hapsyn-mean_isotropy.so"), files
' "$tmp/out/result.json" || fail "result.json check"

passed=$((passed + 1))
echo "out-of-tree plugin: $passed passed, $failed failed"
