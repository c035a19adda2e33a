#!/bin/sh
# Runs the benchmark programs given as arguments, then the command-level
# benchmarks. Benchmarks print figures and never fail on time.
set -u
for b in "$@"; do
    "$b" || echo "bench: $(basename "$b") exited with $?"
done
BTFCAR=${BTF_CLI:-build/btfcar}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
echo "== generate: 81 x 81 images, wall time (median of 3) and peak RSS"
for size in 128 256; do
    times=""
    for run in 1 2 3; do
        rm -rf "$TMP/g"
        /usr/bin/time -f "%e %M" -o "$TMP/time" "$BTFCAR" generate -q --material leather \
            --size "$size" "$TMP/g" || echo "bench: generate failed"
        times="$times $(cut -d' ' -f1 "$TMP/time")"
        rss=$(cut -d' ' -f2 "$TMP/time")
    done
    med=$(echo $times | tr ' ' '\n' | sort -n | sed -n 2p)
    bytes=$(du -sb "$TMP/g" | cut -f1)
    echo "generate leather ${size}x${size}: median ${med} s (runs:${times}), $(echo "6561 $med" | awk '{printf "%.0f", $1/$2}') images/s, peak RSS $((rss / 1024)) MB, $bytes bytes on disk"
done
times=""
for run in 1 2 3; do
    /usr/bin/time -f "%e" -o "$TMP/time" "$BTFCAR" info -q "$TMP/g" >/dev/null
    times="$times $(cat "$TMP/time")"
done
echo "info (probe 6561 files): median $(echo $times | tr ' ' '\n' | sort -n | sed -n 2p) s"
times=""
for run in 1 2 3; do
    /usr/bin/time -f "%e" -o "$TMP/time" "$BTFCAR" info -q --verify "$TMP/g" >/dev/null
    times="$times $(cat "$TMP/time")"
done
echo "info --verify (decode 6561 JPEGs of 256^2): median $(echo $times | tr ' ' '\n' | sort -n | sed -n 2p) s"
