# Sourced by the scripts in scripts/: install_missing PKG... installs, with
# apt-get, only the Debian packages that are not installed yet (root needed
# then; exit 2 with the list otherwise).

# What fgcal itself builds against (Debian 12 package names, docs/toolchain.md);
# each script adds what its own part needs. The Python module: pybind11-dev and
# python3-dev to build it for /usr/bin/python3, python3-numpy to use it,
# python3-pytest for its tests; python3-matplotlib is optional (the plot of
# examples/python/table1.py only: without it the example prints its table and
# says it made no plot).
FGCAL_PACKAGES=(cmake g++ ninja-build pkg-config libeigen3-dev libsuitesparse-dev libopencv-dev
                liburdfdom-dev catch2 libyaml-cpp-dev libcli11-dev liborocos-kdl-dev
                libsqlite3-dev libzstd-dev liblz4-dev libbz2-dev
                pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib)

install_missing() {
  local missing=() p
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "== installing missing packages: ${missing[*]}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "error: these Debian packages are missing and installing them needs root: ${missing[*]}" >&2
    exit 2
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq "${missing[@]}" >/dev/null
}
