#!/bin/sh
# The main job end to end on a generated sample:
#   1. generate a procedural material (81 x 81 images) in the UBO2003 layout;
#   2. read it back and describe it;
#   3. analyse it into one model file (segmentation, range map, CAR models);
#   4. synthesise every subspace image at twice the measured size, seamless;
#   5. render the material on a sphere and a cylinder under two lights, and a
#      flat (view, light) sample beside the measured image of that pair;
#   6. write the report: compression, quality per direction, the preview.
# Usage: examples/demo.sh [PATH/TO/btfcar]   (make demo passes build/btfcar)
set -eu
BTFCAR=${1:-build/btfcar}
OUT=${DEMO_DIR:-build/demo}
MATERIAL=${DEMO_MATERIAL:-leather}
SIZE=${DEMO_SIZE:-128}
BIG=$((SIZE * 2))

EXAMPLES=$(dirname "$0")
rm -rf "$OUT/$MATERIAL" "$OUT/$MATERIAL.btfcar" "$OUT/$MATERIAL-segments" "$OUT/$MATERIAL-synth" \
    "$OUT/$MATERIAL-scene.png" "$OUT/$MATERIAL-flat.png" "$OUT/$MATERIAL-model.png" \
    "$OUT/$MATERIAL-report"
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
echo "== 5a. btfcar render --scene $EXAMPLES/demo.json (a sphere and a cylinder, two lights)"
"$BTFCAR" render "$OUT/$MATERIAL.btfcar" --scene "$EXAMPLES/demo.json" --size 640x400 \
    -o "$OUT/$MATERIAL-scene.png"
echo
echo "== 5b. btfcar render --view 30,60 --light 45,0 --beside the dataset (measured | model)"
"$BTFCAR" render "$OUT/$MATERIAL.btfcar" --view 30,60 --light 45,0 \
    --beside "$OUT/$MATERIAL" -o "$OUT/$MATERIAL-flat.png"
echo
echo "== 5c. the same pair on a surface twice the sample's size (the measured structure quilted)"
"$BTFCAR" render "$OUT/$MATERIAL.btfcar" --view 30,60 --light 45,0 \
    --size "${BIG}x${BIG}" -o "$OUT/$MATERIAL-model.png"
echo
echo "== 6. btfcar report (compression, quality per direction, the preview)"
"$BTFCAR" report "$OUT/$MATERIAL" "$OUT/$MATERIAL.btfcar" -o "$OUT/$MATERIAL-report"
echo
echo "demo: dataset in $OUT/$MATERIAL/ (ground truth in truth/), index table picture"
echo "      $OUT/$MATERIAL-segments/index.png, model $OUT/$MATERIAL.btfcar, synthesised"
echo "      subspace images in $OUT/$MATERIAL-synth/subspace_NN.{exr,png}, the rendered"
echo "      scene $OUT/$MATERIAL-scene.png, and the measured image of (view 30,60; light"
echo "      45,0) beside the model's flat render of it in $OUT/$MATERIAL-flat.png, and"
echo "      the model's render of that pair at twice the size in $OUT/$MATERIAL-model.png"
echo "report: open $OUT/$MATERIAL-report/index.html in a browser (numbers in report.json)"
