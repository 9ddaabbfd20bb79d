#!/usr/bin/env bash
# Every example scene loads and runs its first frames, into pictures and an animation.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

for scene in "$EXAMPLES"/*.json; do
  name=$(basename "$scene" .json)
  expect_exit 0 "$TETCUT" sim "$scene" -o "ex_$name" --frames 2 --animation "ex_$name.gif"
  [[ -s ex_$name/frame_0002.png && -s ex_$name.gif ]] || fail "$name: no pictures or no animation"
done
echo "example pictures: all checks passed"
