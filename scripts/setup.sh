# Shared by scripts/demo and scripts/test (sourced, not run): installs the Debian packages
# canalsim needs when they are missing, then configures and builds one build directory.
# Works on a fresh Debian 12 machine as root (or with sudo).

CANALSIM_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# Build tools and libraries, all from Debian 12 (bookworm). clang-14 and libclang-rt-14-dev
# (libFuzzer) build the fuzz targets only (fuzz/, scripts/fuzz); everything else uses g++.
CANALSIM_PACKAGES=(
  g++ cmake ninja-build pkg-config
  libeigen3-dev libsundials-dev libsuitesparse-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev libtomlplusplus-dev nlohmann-json3-dev libnlopt-cxx-dev libceres-dev
  clang-14 libclang-rt-14-dev
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
