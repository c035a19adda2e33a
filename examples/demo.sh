#!/bin/sh
# The main job end to end on a generated sample: make a procedural material in
# the UBO2003 layout, then read it back and describe it. Later stages (analyse,
# synthesise, render, report) join here as they land.
# Usage: examples/demo.sh [PATH/TO/btfcar]   (make demo passes build/btfcar)
set -eu
BTFCAR=${1:-build/btfcar}
OUT=${DEMO_DIR:-build/demo}
MATERIAL=${DEMO_MATERIAL:-leather}
SIZE=${DEMO_SIZE:-128}

rm -rf "$OUT/$MATERIAL"
mkdir -p "$OUT"
echo "== btfcar generate --material $MATERIAL --size $SIZE $OUT/$MATERIAL"
"$BTFCAR" generate --material "$MATERIAL" --size "$SIZE" --seed 1 "$OUT/$MATERIAL"
echo
echo "== btfcar info $OUT/$MATERIAL"
"$BTFCAR" info "$OUT/$MATERIAL"
echo
echo "demo: images in $OUT/$MATERIAL/tvCCC_pvDDD/, ground truth in $OUT/$MATERIAL/truth/"
