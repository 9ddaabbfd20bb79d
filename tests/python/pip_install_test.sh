#!/usr/bin/env bash
# pip install --no-build-isolation of the checkout into a fresh virtual environment, offline; then
# the installed package, imported from outside the source tree, cuts Figure 4 and runs the example.
set -euo pipefail
rm -rf "$WORK"
mkdir -p "$WORK"
# System site packages: Debian's numpy, meshio and wheel (nothing can be downloaded).
"$PYTHON" -m venv --system-site-packages "$WORK/venv"
"$WORK/venv/bin/pip" install --no-build-isolation --no-index --quiet "$SOURCE"
cd "$WORK"
"$WORK/venv/bin/python" - <<'PY'
import pathlib
import numpy as np
import tetcut
assert pathlib.Path(tetcut.__file__).is_relative_to(pathlib.Path("venv").resolve()), tetcut.__file__
V, T = tetcut.make_grid((0, 0, 0), (1, 1, 1), (4, 4, 4))
cutter = tetcut.Cutter(V, T)
for axis in (0, 1):
    for i in range(1, 17):
        S = np.zeros((4, 3))
        S[:, axis] = i / 17
        S[:, 1 - axis] = [-1, 2, 2, -1]
        S[:, 2] = [-1, -1, 2, 2]
        cutter.cut(S, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32))
assert cutter.result().num_pieces == 289
print("installed tetcut", tetcut.__version__, "from", tetcut.__file__, ": Figure 4 in 289 pieces")
PY
"$WORK/venv/bin/python" "$SOURCE/examples/python/cut_and_simulate.py" "$WORK/series" --steps 30
test -s "$WORK/series/mesh.pvd"
"$WORK/venv/bin/pip" uninstall --yes --quiet tetcut
echo "pip install test passed"
