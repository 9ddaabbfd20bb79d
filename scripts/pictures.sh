#!/usr/bin/env bash
# Every example's pictures, into out/examples (or the directory given): the C++ examples' PNGs
# (and the scalpel's GIF), and for each scene in examples/*.json its frames as PNGs, a GIF and a
# web viewer page (open out/examples/NAME/view.html in a browser).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake --preset release > /dev/null
cmake --build --preset release -j "$(nproc)"
out=${1:-out/examples}
mkdir -p "$out"
for example in cut_a_cube paper_figures scalpel lips cloth_spiral; do
  ./build/release/examples/example_$example "$out"
done
for scene in examples/*.json; do
  name=$(basename "$scene" .json)
  ./build/release/bin/tetcut sim "$scene" -o "$out/$name" --animation "$out/$name.gif"
  ./build/release/bin/tetcut view "$out/$name"
done
echo "pictures: $(cd "$out" && ls ./*.png ./*.gif | tr '\n' ' ')in $out"
