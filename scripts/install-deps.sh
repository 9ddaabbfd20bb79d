#!/usr/bin/env bash
# Installs everything tetcut needs to build, test and benchmark, from Debian 12 packages only.
# Idempotent: packages already present are not downloaded again, and `apt-get update` runs only
# when a package is missing. Must run as root (or through sudo).
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libtbb-dev libgmp-dev
  libcli11-dev nlohmann-json3-dev libfmt-dev libpugixml-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  # Independent tools the tests cross-check against: TetGen writes meshes we must read, meshio
  # (Debian's Python 3) reads what we write.
  tetgen python3-meshio python3-numpy
  # Offscreen rendering (tetcut render): EGL and OpenGL ES 3 headers, Mesa's EGL and software
  # rasteriser (no GPU needed), libpng.
  libegl-dev libgles-dev libegl-mesa0 libgl1-mesa-dri libpng-dev
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

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
