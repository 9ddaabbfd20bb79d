#!/usr/bin/env bash
# The live session in one command: install dependencies, build (Release), and start
# `tetcut serve` on the default scene (the CT femur from libcgal-demo in an 11k-tet lattice).
# It prints an address with a token: open it in a browser on this machine. Ctrl-C stops it.
# Arguments go to tetcut serve (e.g. a scene file, --port 0, --record take.json).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake --preset release > /dev/null
cmake --build --preset release -j "$(nproc)"
exec ./build/release/bin/tetcut serve "$@"
