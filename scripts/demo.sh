#!/usr/bin/env bash
# README command 1: install dependencies, build (Release), and run the default job, which needs
# no input: the paper's Figures 4 and 2 cut exactly, then Figure 8's slinky carved out of a block
# and simulated. Outputs go to ./out: open out/slinky/view.html in a browser (or
# out/slinky/surface.pvd in ParaView); out/slinky.gif is the animation.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake --preset release > /dev/null
cmake --build --preset release -j "$(nproc)"
./build/release/bin/tetcut demo -o out
./build/release/bin/tetcut sim examples/fig8-slinky.json -o out/slinky --animation out/slinky.gif
./build/release/bin/tetcut view out/slinky
