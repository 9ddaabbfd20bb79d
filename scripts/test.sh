#!/usr/bin/env bash
# README command 2: install dependencies, then build and run every test twice: a Release build
# with warnings as errors, and an AddressSanitizer + UndefinedBehaviorSanitizer build.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
jobs=$(nproc)
# Each phase's wall time, so that a slow CI run says where its minutes went.
for preset in release asan; do
  echo "== $preset: configure and build"
  start=$SECONDS
  # Unity build: each compiler run takes several sources, so Eigen, TBB, Boost.Beast and GoogleTest
  # are parsed a few times instead of once per file (a Release build 4 min instead of 7 on 2 cores).
  cmake --preset "$preset" -DCMAKE_UNITY_BUILD=ON > /dev/null
  cmake --build --preset "$preset" -j "$jobs"
  echo "== $preset: built in $((SECONDS - start)) s; test"
  start=$SECONDS
  ctest --preset "$preset" -j "$jobs"
  echo "== $preset: tested in $((SECONDS - start)) s"
done
