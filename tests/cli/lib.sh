# Helpers for the CLI test scripts. Each script runs with `set -euo pipefail` and these
# environment variables from CTest: TETCUT (the binary), TETGEN, PYTHON (Debian's python3), DATA.

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
SCRIPTS=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
cd "$WORK"

fail() { echo "FAIL: $*" >&2; exit 1; }

# expect_exit CODE CMD...: runs CMD, checks its exit code, keeps stdout/stderr in out.txt/err.txt.
expect_exit() {
  local want=$1; shift
  set +e
  "$@" > out.txt 2> err.txt
  local got=$?
  set -e
  [[ $got == "$want" ]] || { cat out.txt err.txt >&2; fail "'$*' exited $got, expected $want"; }
}

# expect_stderr TEXT: the last command's stderr contains TEXT.
expect_stderr() { grep -qF -- "$1" err.txt || { cat err.txt >&2; fail "stderr lacks '$1'"; }; }
expect_stdout() { grep -qF -- "$1" out.txt || { cat out.txt >&2; fail "stdout lacks '$1'"; }; }

# json_check FILE EXPR: evaluates a Python expression over the JSON document `j`.
json_check() {
  "$PYTHON" -c "import json,sys; j=json.load(open(sys.argv[1])); assert $2, (sys.argv[2], j)" "$1" "$2" \
    || fail "JSON check failed: $2"
}
