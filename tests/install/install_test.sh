#!/usr/bin/env bash
# cmake --install puts the library, headers and package config under a prefix; a project outside
# the tree finds it with find_package(tetcut), links tetcut::tetcut and cuts Figure 4 into 289.
set -euo pipefail
rm -rf "$WORK"
mkdir -p "$WORK"
cmake --install "$BUILD" --prefix "$WORK/prefix" > "$WORK/install.log"
test -f "$WORK/prefix/include/tetcut/cutter.hpp"
test -f "$WORK/prefix/lib/cmake/tetcut/tetcutConfig.cmake"
ls "$WORK"/prefix/lib/libtetcut.a > /dev/null
cmake -S "$SOURCE/tests/install/consumer" -B "$WORK/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$WORK/prefix" > "$WORK/configure.log"
cmake --build "$WORK/consumer" > "$WORK/build.log"
pieces=$("$WORK/consumer/consumer")
[[ $pieces == 289 ]] || { echo "the consumer printed '$pieces', not 289"; exit 1; }
echo "install test passed: an outside project cut Figure 4 into $pieces pieces"
