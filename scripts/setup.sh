# Shared by scripts/demo and scripts/test (sourced, not run): installs the Debian packages
# canalsim needs when they are missing, then configures and builds one build directory.
# Works on a fresh Debian 12 machine as root (or with sudo).

CANALSIM_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# Build tools and libraries, all from Debian 12 (bookworm). clang-14 and libclang-rt-14-dev
# (libFuzzer) build the fuzz targets only (fuzz/, scripts/fuzz); everything else uses g++. The
# Python package (python/) needs the interpreter's headers and pybind11; numpy, pandas, pytest
# and matplotlib (the worked example's plots) come from Debian too, for Debian's /usr/bin/python3.
# Open MPI (libopenmpi-dev, openmpi-bin) runs sweeps and blind tests on several processes
# (`mpirun -n N canalsim sweep|blindtest`; the tests run it on two).
CANALSIM_PACKAGES=(
  g++ cmake ninja-build pkg-config
  libeigen3-dev libsundials-dev libsuitesparse-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev libtomlplusplus-dev nlohmann-json3-dev libnlopt-cxx-dev libceres-dev
  clang-14 libclang-rt-14-dev
  python3-dev pybind11-dev python3-numpy python3-pandas python3-pytest python3-matplotlib
  libopenmpi-dev openmpi-bin
)

canalsim_log() { printf '==> %s\n' "$*" >&2; }

canalsim_install_packages() {
  local missing=()
  local pkg
  for pkg in "${CANALSIM_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q 'install ok installed' || missing+=("$pkg")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  local sudo=()
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "error: packages missing (${missing[*]}) and not root; install them or run as root" >&2; return 1; }
    sudo=(sudo)
  fi
  canalsim_log "installing missing packages: ${missing[*]}"
  "${sudo[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# canalsim_build DIR [cmake options...]: configure (once) and build DIR with Ninja.
canalsim_build() {
  local dir="$1"; shift
  canalsim_log "configuring $dir"
  cmake -S "$CANALSIM_ROOT" -B "$dir" -G Ninja "$@" >"$dir.configure.log" 2>&1 \
    || { cat "$dir.configure.log" >&2; return 1; }
  canalsim_log "building $dir (log: $dir.build.log)"
  cmake --build "$dir" -j "$(nproc)" >"$dir.build.log" 2>&1 \
    || { tail -n 60 "$dir.build.log" >&2; return 1; }
}

# canalsim_install BUILD_DIR: installs the program and the Python package under /usr/local
# (`cmake --install`; as root, or with sudo). Debian's python3 finds the package there. When the
# python3 first on PATH is another interpreter of the same version (a pyenv one, say), which does
# not look in Debian's directories, a canalsim-debian.pth in its site-packages adds them (after
# its own), so that `python3 -c "import canalsim"` works with whichever python3 the shell finds.
canalsim_install() {
  local dir="$1"
  local sudo=()
  [ "$(id -u)" -ne 0 ] && sudo=(sudo)
  canalsim_log "installing canalsim and the Python package under /usr/local"
  "${sudo[@]}" cmake --install "$dir" --prefix /usr/local >"$dir.install.log" 2>&1 \
    || { cat "$dir.install.log" >&2; return 1; }
  local python
  python="$(command -v python3 || true)"
  [ -z "$python" ] || [ "$python" = /usr/bin/python3 ] && return 0
  "$python" -c "import canalsim" >/dev/null 2>&1 && return 0
  local debian_version other_version site
  debian_version="$(/usr/bin/python3 -c 'import sys; print("%d.%d" % sys.version_info[:2])')"
  other_version="$("$python" -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null || true)"
  if [ "$debian_version" != "$other_version" ]; then
    canalsim_log "note: $python is Python $other_version; the package is for Debian's /usr/bin/python3 ($debian_version)"
    return 0
  fi
  site="$("$python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
  printf '%s\n' "/usr/local/lib/python$debian_version/dist-packages" /usr/lib/python3/dist-packages \
    | "${sudo[@]}" tee "$site/canalsim-debian.pth" >/dev/null
  canalsim_log "$python: added Debian's package directories to it ($site/canalsim-debian.pth)"
}
