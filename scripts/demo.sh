#!/usr/bin/env bash
# README command 1: install dependencies, build (Release), and run the default job, which needs
# no input. Outputs go to ./out.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake --preset release > /dev/null
cmake --build --preset release -j "$(nproc)"
./build/release/bin/tetcut demo -o out
