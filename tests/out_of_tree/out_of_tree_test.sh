#!/usr/bin/env bash
# The "write your own plugin" path, end to end, for every example in examples/ (mean_isotropy: a
# metric, planar_disc: a scene, planar_2r: a mechanism, random_search: a solver), against the
# *installed* package and against the *build tree*:
#   1. install the build tree into a temporary prefix; the installed hapsyn alone finds its
#      installed built-in plugins; the build tree holds its own package files;
#   2. configure and build every example with find_package(hapsyn), once from the prefix
#      (CMAKE_PREFIX_PATH) and once from the build tree (hapsyn_DIR), both with pagmo's CMake
#      package made unfindable (a plugin that does not use pagmo must not need it), both without
#      a compiler warning (the two trees build in parallel);
#   3. run the examples' self-tests (planar_2r_test);
#   4. with each tree's own hapsyn (the installed bin/hapsyn, the build tree's bin/hapsyn) and
#      HAPSYN_PLUGIN_PATH at the example plugins built against that tree: list and describe them,
#      run each example's study.json and check its result against a value computed
#      independently (check_example.py: the examples' analytic cases, another plugin's output).
# Usage: out_of_tree_test.sh <hapsyn build dir> <hapsyn source dir>
# Uses nothing but the build tree and a temporary directory (removed on exit).
set -euo pipefail

if [[ $# -ne 2 ]]; then
  echo "usage: $0 <build dir> <source dir>" >&2
  exit 2
fi
build_dir=$(cd "$1" && pwd)
source_dir=$(cd "$2" && pwd)
examples_dir="$source_dir/examples"
check="$source_dir/tests/out_of_tree/check_example.py"
examples=(mean_isotropy planar_disc planar_2r random_search)

tmp=$(mktemp -d "${TMPDIR:-/tmp}/hapsyn-oot.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

passed=0
step() { echo "--- $*"; }
ok() { passed=$((passed + 1)); }
fail() {
  echo "FAIL: $*" >&2
  echo "out-of-tree plugins: $passed passed, 1 failed"
  exit 1
}

prefix="$tmp/prefix"

step "install $build_dir into $prefix"
cmake --install "$build_dir" --prefix "$prefix" >"$tmp/install.log" || { cat "$tmp/install.log"; fail "cmake --install"; }
for f in bin/hapsyn include/hapsyn/plugin.hpp include/hapsyn/options.hpp include/hapsyn/metric.hpp \
         lib/cmake/hapsyn/hapsynConfig.cmake lib/cmake/hapsyn/hapsynConfigVersion.cmake \
         lib/cmake/hapsyn/hapsynTargets.cmake lib/cmake/hapsyn/HapsynPlugin.cmake \
         lib/hapsyn/plugins/hapsyn-fivebar.so; do
  [[ -e "$prefix/$f" ]] || fail "the install tree lacks $f"
done
ls "$prefix"/lib/libhapsyn.so* >/dev/null 2>&1 || fail "the install tree lacks lib/libhapsyn.so"
for f in hapsynConfig.cmake hapsynConfigVersion.cmake hapsynTargets.cmake HapsynPlugin.cmake; do
  [[ -e "$build_dir/$f" ]] || fail "the build tree lacks $f (find_package(hapsyn) with hapsyn_DIR=$build_dir)"
done
if grep -v '^ *#' "$prefix/lib/cmake/hapsyn/hapsynConfig.cmake" | grep -i pagmo; then
  fail "hapsynConfig.cmake looks for pagmo, a private dependency of libhapsyn"
fi
ok

step "the installed binary resolves the installed libhapsyn"
ldd_out=$(ldd "$prefix/bin/hapsyn") || fail "ldd $prefix/bin/hapsyn"
grep -q "libhapsyn.*=> $prefix/" <<<"$ldd_out" || { echo "$ldd_out"; fail "ldd: bin/hapsyn does not use $prefix/lib/libhapsyn"; }
if grep -q "not found" <<<"$ldd_out"; then echo "$ldd_out"; fail "ldd: unresolved libraries"; fi
ok

step "the installed hapsyn alone finds the installed built-in plugins"
builtin=$(env -u HAPSYN_PLUGIN_PATH "$prefix/bin/hapsyn" plugins) || fail "hapsyn plugins (no HAPSYN_PLUGIN_PATH)"
grep -Eq "^fivebar +mechanism .*$prefix/lib/hapsyn/plugins/hapsyn-fivebar\.so" <<<"$builtin" ||
  { echo "$builtin"; fail "'hapsyn plugins' does not list the installed fivebar"; }
ok

# The compiler (and its launcher, e.g. ccache) hapsyn was built with. With ccache, paths below
# $tmp are hashed relative to it, so that a rerun of this test reuses the compiled examples.
cache_entry() { sed -n "s/^$1:[A-Z]*=//p" "$build_dir/CMakeCache.txt"; }
compiler=(-DCMAKE_CXX_COMPILER="$(cache_entry CMAKE_CXX_COMPILER)")
launcher=$(cache_entry CMAKE_CXX_COMPILER_LAUNCHER)
[[ -n "$launcher" ]] && compiler+=(-DCMAKE_CXX_COMPILER_LAUNCHER="$launcher")
export CCACHE_BASEDIR="$tmp" CCACHE_NOHASHDIR=1

# build_examples <tree> <expected hapsyn_DIR> <find_package arguments>...: every example into
# $tmp/<tree>/<example>; prints the log of what failed. pagmo made unfindable: see the header.
build_examples() {
  local tree=$1 expected_dir=$2 example dir
  shift 2
  for example in "${examples[@]}"; do
    dir="$tmp/$tree/$example"
    if ! cmake -S "$examples_dir/$example" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "${compiler[@]}" "$@" \
         -DPagmo_DIR=/nonexistent -DCMAKE_DISABLE_FIND_PACKAGE_Pagmo=ON >"$dir.configure.log" 2>&1; then
      cat "$dir.configure.log"; echo "configuring $example against the $tree failed"; return 1
    fi
    if [[ "$(sed -n 's/^hapsyn_DIR:[A-Z]*=//p' "$dir/CMakeCache.txt")" != "$expected_dir" ]]; then
      grep '^hapsyn_DIR' "$dir/CMakeCache.txt"; echo "$example found hapsyn elsewhere than $expected_dir"; return 1
    fi
    if ! cmake --build "$dir" >"$dir.build.log" 2>&1; then
      cat "$dir.build.log"; echo "building $example against the $tree failed"; return 1
    fi
    if grep -q "warning:" "$dir.build.log"; then
      cat "$dir.build.log"; echo "$example compiles with warnings against the $tree"; return 1
    fi
    [[ -f "$dir/plugins/hapsyn-$example.so" ]] || { echo "no $dir/plugins/hapsyn-$example.so"; return 1; }
  done
}

step "build ${examples[*]} against $prefix and against $build_dir (in parallel)"
mkdir -p "$tmp/installed" "$tmp/build-tree"
build_examples installed "$prefix/lib/cmake/hapsyn" -DCMAKE_PREFIX_PATH="$prefix" >"$tmp/installed.log" 2>&1 &
installed_job=$!
build_examples build-tree "$build_dir" -Dhapsyn_DIR="$build_dir" >"$tmp/build-tree.log" 2>&1 &
build_tree_job=$!
wait "$installed_job" || { cat "$tmp/installed.log"; fail "the examples against the installed package"; }
wait "$build_tree_job" || { cat "$tmp/build-tree.log"; fail "the examples against the build tree"; }
ok

# run_examples <tree> <hapsyn>: plugins listed and described, studies run and checked.
run_examples() {
  local tree=$1 hapsyn=$2 example path=""
  local out="$tmp/$tree/out"
  for example in "${examples[@]}"; do path+="${path:+:}$tmp/$tree/$example/plugins"; done
  export HAPSYN_PLUGIN_PATH="$path"

  step "[$tree] planar_2r_test (the Jacobian against finite differences, IK, options)"
  "$tmp/$tree/planar_2r/planar_2r_test" || fail "[$tree] planar_2r_test"
  ok

  step "[$tree] hapsyn plugins / describe"
  local listing kind
  listing=$("$hapsyn" plugins) || fail "[$tree] hapsyn plugins"
  for example in "${examples[@]}"; do
    case $example in mean_isotropy) kind=metric ;; planar_disc) kind=scene ;; planar_2r) kind=mechanism ;; *) kind=solver ;; esac
    grep -Eq "^$example +$kind .*$tmp/$tree/$example/plugins/hapsyn-$example\.so" <<<"$listing" ||
      { echo "$listing"; fail "[$tree] 'hapsyn plugins' does not list $example"; }
  done
  grep -Eq "^fivebar +mechanism " <<<"$listing" || { echo "$listing"; fail "[$tree] 'hapsyn plugins' lost the built-in plugins"; }
  describe() {  # <plugin> <regular expression of an option line>
    local text
    text=$("$hapsyn" describe "$1") || fail "[$tree] hapsyn describe $1"
    grep -Eq "$2" <<<"$text" || { echo "$text"; fail "[$tree] 'hapsyn describe $1' does not show /$2/"; }
  }
  describe mean_isotropy "^ +exponent +number +default 1(\.0)? .*\[>= 0\.1\]"
  describe planar_disc "^ +radius +number +default 0\.05 +m .*\[> 0(\.0)?\]"
  describe planar_2r '^ +q2_sign +string +default "positive" .*\[one of \["positive","negative"\]\]'
  describe planar_2r "^ +l1 +real \[0\.05, 0\.5\] m"
  describe random_search "^ +samples +integer +default 200 "
  ok

  run() {  # <example> <output name> [<study>]: hapsyn run, quietly unless it fails
    local study=${3:-$examples_dir/$1/study.json}
    "$hapsyn" run "$study" --out "$out/$2" --quiet >"$out.$2.log" 2>&1 || { cat "$out.$2.log"; fail "[$tree] hapsyn run $study"; }
  }
  step "[$tree] examples/mean_isotropy/study.json: mean_isotropy against gii's per-sample singular values"
  run mean_isotropy mean_isotropy
  python3 "$check" mean_isotropy "$out/mean_isotropy" || fail "[$tree] mean_isotropy result"
  ok
  step "[$tree] examples/planar_disc/study.json: the samples as documented, the GII over them"
  run planar_disc planar_disc
  python3 "$check" planar_disc "$out/planar_disc" "$examples_dir/planar_disc/study.json" "$out/mean_isotropy" ||
    fail "[$tree] planar_disc result"
  ok
  step "[$tree] examples/planar_2r/study.json: the grid optimum against a brute force from the closed forms"
  run planar_2r planar_2r
  python3 "$check" planar_2r "$out/planar_2r" "$examples_dir/planar_2r/study.json" || fail "[$tree] planar_2r result"
  ok
  step "[$tree] examples/random_search/study.json: its best design evaluated again by evaluate"
  run random_search random_search
  python3 "$check" fixed_design_study "$examples_dir/random_search/study.json" "$out/random_search" "$out/evaluate.json" ||
    fail "[$tree] random_search result"
  run random_search random_search_evaluated "$out/evaluate.json"
  python3 "$check" random_search "$out/random_search" "$out/random_search_evaluated" || fail "[$tree] random_search result"
  ok
}

run_examples installed "$prefix/bin/hapsyn"
run_examples build-tree "$build_dir/bin/hapsyn"

echo "out-of-tree plugins: $passed passed, 0 failed"
