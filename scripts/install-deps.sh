#!/usr/bin/env bash
# Installs the Debian 12 packages proctex needs, only those that are missing.
# Usage: scripts/install-deps.sh [--with-bench]
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  ocl-icd-opencl-dev opencl-clhpp-headers opencl-c-headers pocl-opencl-icd clinfo
  libopenimageio-dev openimageio-tools libpng-dev libjpeg-dev
  libfftw3-dev libnlopt-cxx-dev libnlopt-dev
  libsqlite3-dev sqlite3
  libcli11-dev nlohmann-json3-dev libfmt-dev libeigen3-dev
  libgtest-dev googletest libbenchmark-dev
  fonts-dejavu-core
  slurm-wlm munge
  libcpp-httplib-dev chromium
)
# proctex serve's browser test drives chromium and the workflow lint runs a pinned npm package:
# node and npm, from Debian unless some other node (with its own npm, e.g. NodeSource's) is there.
if ! command -v npm >/dev/null 2>&1; then
  packages+=(nodejs npm)
fi
if [[ "${1:-}" == "--with-bench" ]]; then
  packages+=(hyperfine python3 python3-numpy python3-sklearn python3-scipy)  # python3: bench/realset/build.py (fetches its own game-data .debs); numpy: bench/fit_selection.py; sklearn: bench/select_classifiers.py; scipy: bench/realset/dedup.py
  # bench_synth: G'MIC (what users run today) and real exemplars from Debian texture packages.
  packages+=(gmic neverball-data extremetuxracer-data colobot-common-textures)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: missing: ${missing[*]}"
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
    SUDO=sudo
  else
    echo "install-deps: error: not root. Run as root, or: sudo apt-get install ${missing[*]}" >&2
    exit 1
  fi
else
  SUDO=
fi

export DEBIAN_FRONTEND=noninteractive
# apt-get update only when the package lists cannot resolve what we need.
if ! $SUDO apt-get install -y --no-install-recommends "${missing[@]}" >/tmp/proctex-apt.log 2>&1; then
  echo "install-deps: refreshing package lists (apt-get update)"
  $SUDO apt-get update -qq
  $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
fi
echo "install-deps: installed ${#missing[@]} packages"
