#!/usr/bin/env bash
# tetcut's files read by meshio, and meshio's files read by tetcut (see meshio_check.py).
set -euo pipefail
source "$(dirname "$0")/lib.sh"
"$PYTHON" "$SCRIPTS/meshio_check.py" "$TETCUT" "$WORK"
