#!/usr/bin/env bash
# fgcal quick start: installs what is missing (Debian 12, as root), builds in
# Release, then runs either the demo or every test.
#   bash scripts/quickstart.sh demo    # build, then run the main job on the built-in default
#   bash scripts/quickstart.sh test    # build, then run every test through ctest
set -euo pipefail
mode="${1:-demo}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FGCAL_BUILD_DIR:-$here/build}"
jobs="$(nproc 2>/dev/null || echo 2)"

packages=(cmake g++ ninja-build pkg-config libeigen3-dev libsuitesparse-dev libopencv-dev
          liburdfdom-dev catch2 libyaml-cpp-dev libcli11-dev liborocos-kdl-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "== installing missing packages: ${missing[*]}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "error: these Debian packages are missing and installing them needs root: ${missing[*]}" >&2
    exit 2
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq "${missing[@]}" >/dev/null
fi

echo "== configuring and building in $build"
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "$jobs"

case "$mode" in
  demo)
    exec "$build/apps/fgcal" demo
    ;;
  test)
    ctest --test-dir "$build" --output-on-failure -j "$jobs"
    ;;
  *)
    echo "usage: $0 demo|test" >&2
    exit 2
    ;;
esac
