#!/usr/bin/env bash
# Installs everything tetcut needs to build, test and benchmark, from Debian 12 packages only.
# Idempotent: packages already present are not downloaded again, and `apt-get update` runs only
# when a package is missing. Must run as root (or through sudo).
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libtbb-dev libgmp-dev
  libcli11-dev nlohmann-json3-dev libfmt-dev libpugixml-dev zlib1g-dev
  # HTTP and WebSocket for the live session (tetcut serve): Boost.Beast, header-only.
  libboost-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  # Independent tools the tests cross-check against: TetGen writes meshes we must read, meshio
  # (Debian's Python 3) reads what we write.
  tetgen python3-meshio python3-numpy
  # The Python module (import tetcut): pybind11 and Python's headers to build it, pytest to test
  # it, venv (with pip) to install it as users do.
  pybind11-dev python3-dev python3-pytest python3-venv
  # Offscreen rendering (tetcut render): EGL and OpenGL ES 3 headers, Mesa's EGL and software
  # rasteriser (no GPU needed), libpng.
  libegl-dev libgles-dev libegl-mesa0 libgl1-mesa-dri libpng-dev
  # Animations of simulations (tetcut sim --animation), and the browser the web viewer's test
  # runs in (headless, WebGL through its software renderer).
  ffmpeg chromium
  # Real scanned surfaces for tests and examples (armadillo, bunny, femur, knot, lion head, ...):
  # /usr/share/doc/libcgal-dev/data.tar.gz.
  libcgal-demo
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

# The web viewer is built with Node.js and npm; Debian's are used where none is installed.
if ! command -v node > /dev/null || ! command -v npm > /dev/null; then missing+=(nodejs npm); fi

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
else
  SUDO=""
  if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The viewer's npm packages (three.js, esbuild, playwright-core), exactly as locked, when missing or
# older than the lock file.
viewer=$(cd "$(dirname "$0")/../viewer" && pwd)
if [[ ! -f $viewer/node_modules/.package-lock.json || $viewer/package-lock.json -nt $viewer/node_modules/.package-lock.json ]]; then
  echo "install-deps: npm ci in viewer/"
  (cd "$viewer" && npm ci --no-audit --no-fund --loglevel=error)
fi
echo "install-deps: done"
