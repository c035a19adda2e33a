#!/bin/sh
# The main job end to end on a generated sample:
#   1. generate a procedural material (81 x 81 images) in the UBO2003 layout;
#   2. read it back and describe it;
#   3. analyse it into one model file (segmentation, range map, CAR models);
#   4. synthesise every subspace image at twice the measured size, seamless.
# Usage: examples/demo.sh [PATH/TO/btfcar]   (make demo passes build/btfcar)
set -eu
BTFCAR=${1:-build/btfcar}
OUT=${DEMO_DIR:-build/demo}
MATERIAL=${DEMO_MATERIAL:-leather}
SIZE=${DEMO_SIZE:-128}
BIG=$((SIZE * 2))

rm -rf "$OUT/$MATERIAL" "$OUT/$MATERIAL.btfcar" "$OUT/$MATERIAL-segments" "$OUT/$MATERIAL-synth"
mkdir -p "$OUT"
echo "== 1. btfcar generate --material $MATERIAL --size $SIZE $OUT/$MATERIAL"
"$BTFCAR" generate --material "$MATERIAL" --size "$SIZE" --seed 1 "$OUT/$MATERIAL"
echo
echo "== 2. btfcar info $OUT/$MATERIAL"
"$BTFCAR" info "$OUT/$MATERIAL"
echo
echo "== 3a. btfcar analyse --stage segment (index table and subspace images)"
"$BTFCAR" analyse "$OUT/$MATERIAL" -o "$OUT/$MATERIAL-segments" --stage segment
echo
echo "== 3b. btfcar analyse $OUT/$MATERIAL -o $OUT/$MATERIAL.btfcar"
"$BTFCAR" analyse "$OUT/$MATERIAL" -o "$OUT/$MATERIAL.btfcar" | head -4
echo
echo "== 4. btfcar synthesise --size ${BIG}x${BIG} (every subspace image)"
"$BTFCAR" synthesise "$OUT/$MATERIAL.btfcar" --size "${BIG}x${BIG}" --preview \
    -o "$OUT/$MATERIAL-synth"
echo
echo "demo: dataset in $OUT/$MATERIAL/ (ground truth in truth/), index table picture"
echo "      $OUT/$MATERIAL-segments/index.png, model $OUT/$MATERIAL.btfcar, synthesised"
echo "      subspace images in $OUT/$MATERIAL-synth/subspace_NN.{exr,png}"
