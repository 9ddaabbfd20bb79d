#!/usr/bin/env bash
# Every example scene loads and runs its first frame, into pictures and an animation (one frame:
# Figure 4's 289 sticks take about 2 s a step while they first collide, 10 s a frame).
set -euo pipefail
source "$(dirname "$0")/lib.sh"

for scene in "$EXAMPLES"/*.json; do
  name=$(basename "$scene" .json)
  expect_exit 0 "$TETCUT" sim "$scene" -o "ex_$name" --frames 1 --animation "ex_$name.gif"
  [[ -s ex_$name/frame_0001.png && -s ex_$name.gif ]] || fail "$name: no pictures or no animation"
done
echo "example pictures: all checks passed"
