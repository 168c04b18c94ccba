#!/usr/bin/env bash
# Development rebuild of the package's C core in place (what `pip install -e .` compiles), safe to run from
# several shells at once: private object directory, atomic swap of the shared library.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-.venv/bin/python}
SUFFIX=$($PY -c "import sysconfig; print(sysconfig.get_config_var('EXT_SUFFIX'))")
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
FLAGS="-std=c99 -O3 -fno-semantic-interposition -fno-tree-slp-vectorize -flto -fPIC -Wall -Wextra -Wpedantic -Wconversion -Wdouble-promotion -Icore/ctrl/include -Icore/host/include"
for f in core/ctrl/src/*.c core/host/src/*.c; do
    cc $FLAGS -c "$f" -o "$TMP/$(basename "$f" .c).o" &
done
wait
cc -shared -flto=auto -O3 "$TMP"/*.o -lm -o "$TMP/lib.so"
mv -f "$TMP/lib.so" "src/bldclab/_bccore$SUFFIX"
echo "built src/bldclab/_bccore$SUFFIX"
