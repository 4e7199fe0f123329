#!/usr/bin/env bash
# Installs the Debian packages hapsyn needs, only those that are missing.
# Quick (a dpkg query) when everything is present. Run as root (or with sudo available).
#   setup.sh            what hapsyn builds with (and npm, which fetches three.js for hapsyn view)
#   setup.sh --browser  only what the browser tests of hapsyn view need (chromium, its driver,
#                       selenium); scripts/test.sh installs these while the build runs
set -euo pipefail

if [[ "${1:-}" == "--browser" ]]; then
  packages=(chromium chromium-driver python3-selenium)
else
packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libboost-dev libboost-filesystem-dev
  libpagmo-dev nlohmann-json3-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libnlopt-cxx-dev liborocos-kdl-dev liburdfdom-dev libtinyxml-dev
  gnuplot-nox
  python3-dev python3-numpy python3-pytest pybind11-dev
  openmpi-bin libopenmpi-dev
  libhwy-dev
  mkdocs doxygen jupyter-nbconvert python3-ipykernel python3-nbformat python3-venv
)
# npm: three.js for the page of hapsyn view (web/package-lock.json). A node.js that brings its
# own npm (another distribution's package) is kept: Debian's npm would conflict with it.
if ! command -v npm >/dev/null 2>&1; then packages+=(nodejs npm); fi
fi
# Extra packages requested through the environment (e.g. HAPSYN_EXTRA_PACKAGES="gnuplot").
if [[ -n "${HAPSYN_EXTRA_PACKAGES:-}" ]]; then
  read -r -a extra <<<"${HAPSYN_EXTRA_PACKAGES}"
  packages+=("${extra[@]}")
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [[ ${#missing[@]} -eq 0 ]]; then
  exit 0
fi

echo "hapsyn setup: installing ${missing[*]}" >&2
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
