#!/bin/sh
# make bench: the benchmark programs given as arguments, then command-level
# benchmarks. Figures only: medians of several runs, throughput, peak memory,
# ratios. Nothing here fails on time. BENCH_FULL=1 adds the 32768^2 synthesis.
# BENCH_BTF400=0 replaces the .btf file of UBO2014's size (400^2, 151 x 151,
# 228 half components, 83.5 MB: about 10 minutes on 2 cores) by a 128^2 one.
set -u
BTFCAR=${BTF_CLI:-build/btfcar}
export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.x86_64.json}
echo "== machine: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GiB", $2/1048576}' /proc/meminfo), $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -1)"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
SYNTH_MODEL=""
RENDER_BENCH=""
FIDELITY_BENCH=""
for b in "$@"; do
    case "$b" in
    *bench_synth_model)
        SYNTH_MODEL=$b ;; # below, on the paper's workload
    *bench_render)
        RENDER_BENCH=$b ;; # below, on the analysed material
    *bench_fidelity)
        FIDELITY_BENCH=$b ;; # below, on the generated materials and photographs
    *bench_btf)
        # A file of the Bonn database's shape (docs/datasets.md, "UBO2014
        # .btf files"): 151 x 151 directions, 400^2 texels, DFMF half floats,
        # 78 + 76 + 74 components (the published sizes of 82.9-84.3 MB imply
        # 226-230 in all), colour model 11: 83,542,344 bytes. Its factors are
        # the 20^2 leather's, S x V tiled. Printed: the bytes against the
        # layout, the open (median of 5), every image reconstructed once (one
        # thread; peak RSS of that process), and btfcar analyse of the file
        # as a user runs it (--threads = the cores, or BENCH_BTF_THREADS):
        # wall, user and system time, peak RSS. About 10 minutes on 2 cores
        # (docs/datasets.md has the figures). BENCH_BTF400=0 runs a
        # 128^2 file of the same directions and components instead (write and
        # read in one process, about 2 minutes); BENCH_BTF_LIB=1 adds
        # btf_analyse called by a program (bench_btf analyse).
        BTF400=$TMP/ubo400.btf
        if [ "${BENCH_BTF400:-1}" = 1 ]; then
            echo "== Bonn .btf of UBO2014's shape: 151 x 151 x 400^2, DFMF half, components 78 76 74, model 11 (bench_btf; factors of the leather at 20^2, S x V tiled); analyse goal <= 5 min, <= 2 GB"
            "$b" write "$BTF400" 400 78,76,74 20 || echo "bench: bench_btf write exited with $?"
            if [ -f "$BTF400" ]; then
                echo "   file: $(stat -c %s "$BTF400") bytes on disk"
                "$b" read "$BTF400" 0 5 || echo "bench: bench_btf read exited with $?"
                threads=${BENCH_BTF_THREADS:-$(nproc)}
                /usr/bin/time -f "%e %U %S %M" -o "$TMP/time" "$BTFCAR" analyse -q --threads "$threads" "$BTF400" -o "$TMP/ubo400.btfcar" >"$TMP/out" 2>"$TMP/err" &&
                    echo "btfcar analyse --threads $threads of the 400^2 .btf, end to end (1 run): $(cut -d' ' -f1 "$TMP/time") s wall, $(cut -d' ' -f2 "$TMP/time") s user, $(cut -d' ' -f3 "$TMP/time") s system, peak RSS $(($(cut -d' ' -f4 "$TMP/time") / 1024)) MB, model $(stat -c %s "$TMP/ubo400.btfcar") bytes" ||
                    echo "bench: analyse of the 400^2 .btf failed: $(tail -1 "$TMP/err")"
                if [ "${BENCH_BTF_LIB:-0}" = 1 ]; then
                    "$b" analyse "$BTF400" || echo "bench: bench_btf analyse exited with $?"
                fi
                rm -f "$BTF400" "$TMP/ubo400.btfcar"
            fi
        else
            echo "== Bonn .btf, small: 151 x 151 x 128^2, DFMF half, components 78 76 74, model 11 (bench_btf; BENCH_BTF400=0)"
            "$b" 128 78,76,74 || echo "bench: bench_btf exited with $?"
        fi ;;
    *bench_rf)
        # the reflectance-field family on an 81 x 81 x 128^2 material: each
        # fit with 2 threads (PTM timed 3 times, the two Levenberg-Marquardt
        # fits once: several minutes each), bytes against the CAR model,
        # flat and sphere renders on the CPU and on lavapipe (docs/rf.md)
        "$b" "${BENCH_RF_SIZE:-128}" leather || echo "bench: bench_rf exited with $?" ;;
    *bench_gpu)
        for n in 1 2; do
            LP_NUM_THREADS=$n "$b" || echo "bench: $(basename "$b") exited with $?"
        done ;;
    *)
        "$b" || echo "bench: $(basename "$b") exited with $?" ;;
    esac
done

median3() { echo "$@" | tr ' ' '\n' | sed '/^$/d' | sort -n | sed -n 2p; }
# timed LABEL CMD...: runs CMD 3 times, prints the median wall time and the
# peak RSS of the last run; leaves the last run's output in place.
timed() {
    label=$1
    shift
    times=""
    for run in 1 2 3; do
        /usr/bin/time -f "%e %M" -o "$TMP/time" "$@" >"$TMP/out" 2>"$TMP/err" ||
            { echo "bench: $label failed: $(tail -1 "$TMP/err")"; return 1; }
        times="$times $(cut -d' ' -f1 "$TMP/time")"
    done
    med=$(median3 $times)
    rss=$(($(cut -d' ' -f2 "$TMP/time") / 1024))
    echo "$label: median $med s (runs:$times), peak RSS $rss MB"
}

echo "== generate: 81 x 81 images"
for size in 128 256; do
    rm -rf "$TMP/g$size"
    timed "generate leather ${size}x${size}" sh -c "rm -rf $TMP/g$size && $BTFCAR generate -q --material leather --size $size $TMP/g$size"
    echo "   $(echo "6561 $med" | awk '{printf "%.0f", $1/$2}') images/s, $(du -sb "$TMP/g$size" | cut -f1) bytes on disk"
done
G=$TMP/g256
timed "info (probe 6561 files of 256^2)" "$BTFCAR" info -q "$G"
timed "info --verify (decode 6561 JPEGs of 256^2)" "$BTFCAR" info -q --verify "$G"

echo "== segmentation: 81 x 81 images of 256^2, target <= 30 s, <= 1 GB"
timed "analyse --stage segment" sh -c "rm -rf $TMP/seg && $BTFCAR analyse $G -o $TMP/seg --stage segment"
echo "   $(echo "$med" | awk '{printf "%.2f", 1000*$1/6561}') ms per image; $(sed -n 1p "$TMP/out")"

echo "== model file: the whole analysis of the 81 x 81 x 256^2 material"
timed "analyse (all stages)" "$BTFCAR" analyse -q "$G" -o "$TMP/m.btfcar"
bytes=$(stat -c %s "$TMP/m.btfcar")
echo "   model $bytes bytes (target <= 16384); ratio to the raw 8-bit images (81*81*256*256*3 = 1289945088 bytes) 1 : $((1289945088 / bytes)); paper ~1 : 10^5"

echo "== the paper's workload through the command: 15 subspace images of 512x512, 3 bands, 3 levels"
# The model: 15 subspaces of the 256^2 material, 3 pyramid levels (as bench_car's).
"$BTFCAR" analyse -q "$G" -o "$TMP/paper.btfcar" --subspaces 15 --levels 3 --no-range
P=$TMP/paper.btfcar
if [ -n "$SYNTH_MODEL" ]; then
    "$SYNTH_MODEL" "$P" 512x512 9 >"$TMP/mem" || echo "bench: bench_synth_model exited with $?"
    sed '/^median_s /d' "$TMP/mem"
    mem=$(sed -n 's/^median_s //p' "$TMP/mem")
fi
# median5 LABEL CMD...: 5 runs of the whole process; median wall time in $med.
median5() {
    label=$1
    shift
    times=""
    for run in 1 2 3 4 5; do
        /usr/bin/time -f "%e %M" -o "$TMP/time" "$@" >"$TMP/out" 2>"$TMP/err" ||
            { echo "bench: $label failed: $(tail -1 "$TMP/err")"; return 1; }
        times="$times $(cut -d' ' -f1 "$TMP/time")"
    done
    med=$(echo $times | tr ' ' '\n' | sort -n | sed -n 3p)
    echo "$label: median $med s (runs:$times), peak RSS $(($(cut -d' ' -f2 "$TMP/time") / 1024)) MB,"\
         "$(du -sb "${MEDIAN5_OUTPUT:-$TMP/p}" | cut -f1) bytes"
}
SYN="$BTFCAR synthesise -q $P --backend cpu --size 512x512 -o $TMP/p"
median5 "synthesise, default options (half, none, writer thread, colour matching)" $SYN
def=$med
[ -n "${mem:-}" ] && echo "   whole process / in-memory synthesis: $(echo "$def $mem" | awk '{printf "%.2f", $1/$2}') (target <= 4)"
median5 "synthesise --no-match-colours" $SYN --no-match-colours
echo "   colour matching costs the whole command $(echo "$def $med" | awk '{printf "%+.1f%%", 100 * ($1 / $2 - 1)}') (target: <= 10 %)"
$SYN -v 2>&1 >/dev/null | sed 's/^/   --verbose: /'
if command -v exrheader >/dev/null 2>&1; then
    exrheader "$TMP/p/subspace_00.exr" >"$TMP/hdr" 2>&1 &&
        echo "   exrheader reads it: $(sed -n 's/^compression (type compression): //p' "$TMP/hdr")"\
             "compression, $(grep -c 'floating-point' "$TMP/hdr") channels of"\
             "$(grep -o '[0-9]*-bit floating-point' "$TMP/hdr" | head -1)" ||
        echo "bench: exrheader cannot read $TMP/p/subspace_00.exr"
else
    echo "   (exrheader not installed: make deps installs openexr)"
fi
median5 "synthesise --float --compression zip (0.3.0's default)" $SYN --float --compression zip
median5 "synthesise, defaults, BTF_EXR_THREAD=0 (one thread)" env BTF_EXR_THREAD=0 $SYN
for c in rle zips zip piz; do
    median5 "synthesise --compression $c" $SYN --compression $c
done

echo "== streaming synthesis to EXR: memory grows with the width, not the height"
for h in 512 2048; do
    timed "synthesise 32768x$h, 1 subspace, cpu" sh -c "rm -rf $TMP/s && $BTFCAR synthesise -q $TMP/m.btfcar --subspace 0 --backend cpu --half --size 32768x$h -o $TMP/s"
done
if [ "${BENCH_FULL:-0}" = 1 ]; then
    /usr/bin/time -f "%e %M" -o "$TMP/time" "$BTFCAR" synthesise -q "$TMP/m.btfcar" --subspace 0 \
        --backend cpu --half --size 32768x32768 -o "$TMP/s"
    echo "synthesise 32768x32768 to half EXR: $(cut -d' ' -f1 "$TMP/time") s, peak RSS $(($(cut -d' ' -f2 "$TMP/time") / 1024)) MB (target <= 256 MB)"
fi

echo "== reflectance fields (docs/rf.md): the PTM fit of the 81 x 81 x 256^2 material through the command, 2 threads"
timed "analyse --family rf --fit ptm" "$BTFCAR" analyse -q "$G" --family rf --fit ptm --threads 2 -o "$TMP/rf.btfcar"
rfbytes=$(stat -c %s "$TMP/rf.btfcar")
echo "   model $rfbytes bytes, $((rfbytes / 65536)) bytes per texel; $((rfbytes / bytes)) x the CAR model's $bytes bytes"
timed "render --view 37.5,100 --light 45,20 (1024^2, 4 views blended)" "$BTFCAR" render -q "$TMP/rf.btfcar" --view 37.5,100 --light 45,20 --size 1024x1024 --threads 2 -o "$TMP/rf.png"
timed "the same, --backend gpu (lavapipe)" "$BTFCAR" render -q "$TMP/rf.btfcar" --view 37.5,100 --light 45,20 --size 1024x1024 --threads 2 --backend gpu -o "$TMP/rf.png"
timed "render --scene (the one-light sphere, 1024^2)" "$BTFCAR" render -q "$TMP/rf.btfcar" --scene "$(dirname "$0")/../../examples/sphere-one-light.json" --size 1024x1024 --threads 2 -o "$TMP/rf.png"
timed "the same, --backend gpu (lavapipe)" "$BTFCAR" render -q "$TMP/rf.btfcar" --scene "$(dirname "$0")/../../examples/sphere-one-light.json" --size 1024x1024 --threads 2 --backend gpu -o "$TMP/rf.png"
rm -f "$TMP/rf.btfcar"

echo "== render: a 1024^2 sphere of the analysed 256^2 material under one light (examples/sphere-one-light.json)"
SPHERE=$(dirname "$0")/../../examples/sphere-one-light.json
if [ -n "$RENDER_BENCH" ]; then
    for n in 1 2; do
        LP_NUM_THREADS=$n "$RENDER_BENCH" "$TMP/m.btfcar" "$SPHERE" 1024x1024 5 ||
            echo "bench: bench_render exited with $?"
    done
fi
MEDIAN5_OUTPUT=$TMP/sphere.png
REN="$BTFCAR render -q $TMP/m.btfcar --scene $SPHERE --size 1024x1024 -o $TMP/sphere.png"
median5 "render the sphere, whole process (needed subspaces only)" $REN
needed=$med
"$BTFCAR" render "$TMP/m.btfcar" --scene "$SPHERE" --size 1024x1024 -o "$TMP/sphere.png" | sed -n 's/^/   /p'
median5 "render the sphere, whole process, --all-subspaces" $REN --all-subspaces
echo "   the needed-only rule saves $(echo "$needed $med" | awk '{printf "%.0f%%", 100 * (1 - $1 / $2)}') of the whole process"

echo "== GPU render past one storage buffer (docs/gpu.md, \"Images left on the device\"): a 4096^2 flat render, a 192 MiB image and 256 MiB of maps over lavapipe's 128 MiB buffers"
FLAT="$BTFCAR render -q $TMP/m.btfcar --view 30,60 --light 45,0 --size 4096x4096"
timed "render 4096x4096 flat, --backend cpu" $FLAT --backend cpu -o "$TMP/flat-cpu.png"
cpu_s=$med
timed "the same, --backend gpu (lavapipe: split over 2-4 buffers)" $FLAT --backend gpu -o "$TMP/flat-gpu.png"
echo "   lavapipe/cpu time ratio $(echo "$med $cpu_s" | awk '{printf "%.2f", $1 / $2}');"\
     "bytes $(cmp -s "$TMP/flat-cpu.png" "$TMP/flat-gpu.png" && echo equal || echo DIFFER)"
rm -f "$TMP/flat-cpu.png" "$TMP/flat-gpu.png"

echo "== fidelity (docs/fidelity.md): texture distances of btfcar's syntheses and the phase-randomisation baseline"
if [ -n "$FIDELITY_BENCH" ]; then
    set --
    for mat in leather fabric wood; do
        "$BTFCAR" generate -q --material $mat --size 128 --seed 3 "$TMP/f$mat" &&
            "$BTFCAR" analyse -q "$TMP/f$mat" -o "$TMP/f$mat-seg" --stage segment &&
            for img in "$TMP/f$mat-seg"/subspace_*.exr; do
                cp "$img" "$TMP/$mat-$(basename "$img")"
                set -- "$@" "$TMP/$mat-$(basename "$img")"
            done
    done
    if sh "$(dirname "$0")/../../tools/fetch-textures.sh" "$TMP/tex" >/dev/null 2>&1; then
        set -- "$@" "$TMP"/tex/*.pat
    else
        echo "   (no photographs: tools/fetch-textures.sh could not download gimp-data)"
    fi
    "$FIDELITY_BENCH" "$@" || echo "bench: bench_fidelity exited with $?"
fi

echo "== report (docs/report.md): the 81 x 81 x 128^2 leather, default sample (81 pairs), target <= 60 s"
R=$TMP/rl
"$BTFCAR" generate -q --material leather --size 128 --seed 1 "$R" &&
    "$BTFCAR" analyse -q "$R" -o "$R.btfcar" || echo "bench: the report's material failed"
MEDIAN5_OUTPUT=$TMP/rep
timed "btfcar report, whole process" sh -c "rm -rf $TMP/rep && $BTFCAR report -q $R $R.btfcar -o $TMP/rep"
report_s=$med
sed -n 's/^[[:space:]]*"seconds":[[:space:]]*\(.*\),$/   report.json seconds: \1/p' "$TMP/rep/report.json" | head -1
echo "   $(du -sb "$TMP/rep" | cut -f1) bytes in $(ls "$TMP/rep" | wc -l) files"
/usr/bin/time -f "%e %M" -o "$TMP/time" "$BTFCAR" report -q "$R" "$R.btfcar" -o "$TMP/rep-all" --all ||
    echo "bench: report --all failed"
echo "report --all (6561 pairs): $(cut -d' ' -f1 "$TMP/time") s, peak RSS $(($(cut -d' ' -f2 "$TMP/time") / 1024)) MB"
/usr/bin/time -f "%e %M" -o "$TMP/time" "$BTFCAR" report -q "$R" "$R.btfcar" -o "$TMP/rep-sw" \
    --sweep --sweep-subspaces auto,4 --sweep-levels auto,2 --sweep-neighbours auto,8 ||
    echo "bench: report --sweep failed"
sw=$(cut -d' ' -f1 "$TMP/time")
echo "report --sweep, 8 settings: $sw s, peak RSS $(($(cut -d' ' -f2 "$TMP/time") / 1024)) MB;" \
     "$(echo "$sw $report_s" | awk '{printf "%.1f", ($1 - $2) / 8}') s per setting beyond the report"
/usr/bin/time -f "%e" -o "$TMP/time" "$BTFCAR" report -q "$R" "$R.btfcar" -o "$TMP/rep-sw" \
    --sweep --sweep-subspaces auto,4 --sweep-levels auto,2 --sweep-neighbours auto,8
echo "   the same again, every point resumed: $(cat "$TMP/time") s"

echo "== structure layers (docs/model.md): before and after on the three 81 x 81 x 128^2 materials"
# Three model formats' worth of analysis, each the whole command: 1.3
# (--no-structure --range-size 64 --no-gains: the CAR fields model every
# exemplar whole), 1.4 (--no-shadows --no-gains: the structure layer alone)
# 1.5 (--no-cells: shadows, masking, registered exemplars, pair gains) and
# 1.7 (the default: with a weave's periodic cells; leather and wood have no
# lattice, so their 1.7 row is their 1.5 model).
# Per row: analysis and 512^2 flat render times (medians of 3, whole
# process), model bytes, the report's mean combined distance.
for mat in leather fabric wood; do
    D=$TMP/s$mat
    [ -d "$D" ] || "$BTFCAR" generate -q --material $mat --size 128 --seed 1 "$D" ||
        { echo "bench: generate $mat failed"; continue; }
    for fmt in 1.3 1.4 1.5 1.7; do
        case $fmt in
        1.3) opts="--no-structure --range-size 64 --no-gains --no-cells" ;;
        1.4) opts="--no-shadows --no-gains --no-cells" ;;
        1.5) opts="--no-cells" ;;
        1.7) opts="" ;;
        esac
        timed "   $mat $fmt: analyse" "$BTFCAR" analyse -q "$D" -o "$D-$fmt.btfcar" $opts >/dev/null || continue
        an=$med
        timed "   $mat $fmt: flat render 512^2" "$BTFCAR" render "$D-$fmt.btfcar" --view 30,60 --light 45,0 \
            --size 512x512 -o "$TMP/flat.png" >/dev/null || continue
        rn=$med
        "$BTFCAR" report -q "$D" "$D-$fmt.btfcar" -o "$TMP/rep-s" || continue
        q=$(sed -n 's/^[[:space:]]*"mean_combined":[[:space:]]*\(.*\),$/\1/p' "$TMP/rep-s/report.json" | head -1)
        echo "$mat format $fmt: analyse $an s, model $(stat -c %s "$D-$fmt.btfcar") bytes, flat render 512^2 $rn s, mean combined distance $q"
    done
done

echo "== the structure map placed on larger surfaces (synthesise --range): quilting, the joins' relaxation, normals"
# docs/render.md, "The structure map (texel 1)": the 128^2 leather's range
# map quilted to 512^2 and 2048^2, the whole command (EXR writing included).
if [ -f "$TMP/sleather-1.7.btfcar" ]; then
    for n in 512 2048; do
        timed "   leather range map ${n}x${n}" sh -c "rm -rf $TMP/rng && $BTFCAR synthesise -q $TMP/sleather-1.7.btfcar --size ${n}x${n} --range --subspace none -o $TMP/rng" || continue
        echo "structure map ${n}^2: $med s, peak RSS $rss MB"
    done
fi

echo "== presets (btfcar analyse --preset): cost and quality on the 128^2 leather"
for p in fast balanced accurate; do
    /usr/bin/time -f "%e" -o "$TMP/time" "$BTFCAR" analyse -q "$R" -o "$TMP/$p.btfcar" --preset $p ||
        { echo "bench: --preset $p failed"; continue; }
    a=$(cat "$TMP/time")
    "$BTFCAR" report -q "$R" "$TMP/$p.btfcar" -o "$TMP/rep-$p" || continue
    q=$(sed -n 's/^[[:space:]]*"mean_combined":[[:space:]]*\(.*\),$/\1/p' "$TMP/rep-$p/report.json" | head -1)
    "$BTFCAR" synthesise -q "$TMP/$p.btfcar" --size 512x512 -o "$TMP/syn-$p" --backend cpu
    median5 "   $p: synthesise every subspace at 512^2" sh -c "rm -rf $TMP/syn-$p && $BTFCAR synthesise -q $TMP/$p.btfcar --size 512x512 -o $TMP/syn-$p --backend cpu" >/dev/null
    echo "$p: analyse $a s, model $(stat -c %s "$TMP/$p.btfcar") bytes, synthesis of every subspace at 512^2 (whole process, median of 5) $med s, mean combined distance $q"
done
