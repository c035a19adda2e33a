#!/bin/sh
# gpu-check.sh [--allow-cpu] [--dry-run]   (make gpu-check builds first)
#
# The real-GPU check (docs/gpu.md, "Checking on a real GPU"): on a
# machine with a Vulkan GPU,
#   1. runs the GPU parity test programs against it (each test turns the
#      Khronos validation layer on itself; bit parity on a CPU device, the
#      stated tolerance on a GPU);
#   2. times four workloads as a user runs them, the whole btfcar command,
#      median of 3 runs, --backend cpu against --backend gpu in the same run:
#      the paper's synthesis (15 subspace images of 512^2), a 1024^2 sphere
#      render, a 4096^2 flat render and a 1024^2 sphere render of a
#      reflectance-field model;
#   3. prints one table: workload | CPU s | GPU s | speed-up | bytes equal
#      (cmp of the CPU's and the GPU's output files), under a line naming
#      the GPU device and the CPU.
# With no real GPU (only lavapipe, a CPU-type device) it says so and exits 0;
# --allow-cpu runs everything on lavapipe instead (which is how the script
# itself is checked on a machine without a GPU). --dry-run prints the
# commands and runs nothing.
#
# Environment: BTF_CLI (default build/btfcar; the test programs are in its
# directory's tests/), BTF_CHECK_PAGE (passed to the tests). BTF_VK_DEVICE is
# ignored: the device is the library's automatic choice (discrete >
# integrated > virtual GPU), the one the test programs take too.
# Exit status: 0 passed (or no GPU); 1 a test or a command failed, or a CPU
# device did not give the CPU's bytes; 2 usage.
set -u
BTFCAR=${BTF_CLI:-build/btfcar}
TESTS=$(dirname "$BTFCAR")/tests
SCENE=$(dirname "$0")/../examples/sphere-one-light.json
PARITY="test_gpu test_gpu_render test_gpu_tileable test_gpu_rf test_gpu_match"
RUNS=3
allow_cpu=0
dry=0
for a in "$@"; do
    case "$a" in
    --allow-cpu) allow_cpu=1 ;;
    --dry-run) dry=1 ;;
    -h | --help)
        sed -n '2,/^set -u/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'
        exit 0 ;;
    *)
        echo "gpu-check: unknown option '$a' (usage: gpu-check.sh [--allow-cpu] [--dry-run])" >&2
        exit 2 ;;
    esac
done
unset BTF_VK_DEVICE BTF_VK_VALIDATION

# The test programs take lavapipe when neither loader variable is set
# (tests/unit/testutil.c); naming every installed driver lets them, like the
# command, see the real GPU. One variable set: the other follows it (the
# loader reads VK_DRIVER_FILES from 1.3.234 on, VK_ICD_FILENAMES before).
all_drivers() {
    list=""
    for d in "${XDG_CONFIG_HOME:-$HOME/.config}/vulkan/icd.d" /etc/xdg/vulkan/icd.d \
        /etc/vulkan/icd.d "${XDG_DATA_HOME:-$HOME/.local/share}/vulkan/icd.d" \
        /usr/local/share/vulkan/icd.d /usr/share/vulkan/icd.d; do
        for f in "$d"/*.json; do
            # a name already listed is the same driver installed twice
            # (nvidia_icd.json is often in /etc and /usr/share): once
            case ":$list" in
            */"${f##*/}":* | */"${f##*/}") continue ;;
            esac
            [ -f "$f" ] && list="${list:+$list:}$f"
        done
    done
    echo "$list"
}
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -z "${VK_ICD_FILENAMES:-}" ]; then
    VK_DRIVER_FILES=$(all_drivers)
fi
VK_DRIVER_FILES=${VK_DRIVER_FILES:-$VK_ICD_FILENAMES}
VK_ICD_FILENAMES=${VK_ICD_FILENAMES:-$VK_DRIVER_FILES}
export VK_DRIVER_FILES VK_ICD_FILENAMES

# ------------------------------------------------------------ the work

W=WORK # the work directory: a fresh one (mktemp) before a real run

# workload I: the row's name, the output (a directory is compared file by
# file) and the btfcar arguments before the output and the backend. The
# flat render's textures are 256^2 so that it measures the render pass over
# 16 M pixels; synthesis is the first row's.
workload() {
    case $1 in
    1) name="synthesise 15 subspaces at 512^2 (paper)" out=synth
       args="synthesise -q $W/car.btfcar --size 512x512 -o" ;;
    2) name="render sphere 1024^2" out=sphere.png
       args="render -q $W/car.btfcar --scene $SCENE --size 1024x1024 -o" ;;
    3) name="render flat 4096^2" out=flat.png
       args="render -q $W/car.btfcar --view 30,60 --light 45,0 --size 4096x4096 --texture-size 256 -o" ;;
    4) name="render RF sphere 1024^2" out=rf.png
       args="render -q $W/rf.btfcar --scene $SCENE --size 1024x1024 -o" ;;
    esac
}

# setup RUNNER: the material and its two models, each command given to
# RUNNER: a generated 128^2 leather (81 x 81 images), the CAR model with the
# paper's 15 subspaces and 3 levels (and a range map, for the renders), the
# PTM reflectance field.
setup() {
    $1 "$BTFCAR" generate -q --material leather --size 128 --seed 1 "$W/leather" &&
        $1 "$BTFCAR" analyse -q "$W/leather" -o "$W/car.btfcar" --subspaces 15 --levels 3 &&
        $1 "$BTFCAR" analyse -q "$W/leather" -o "$W/rf.btfcar" --family rf --fit ptm
}

# backend_args BACKEND: what a timed command adds for it.
backend_args() {
    if [ "$1" = cpu ]; then echo "--backend cpu"; else echo "--backend gpu --device $device"; fi
}

if [ "$dry" = 1 ]; then
    device=N
    echo "# parity tests, side by side with the setup (untimed; VK_DRIVER_FILES=$VK_DRIVER_FILES)"
    for t in $PARITY; do
        echo "BTF_CLI=$BTFCAR $TESTS/$t"
    done
    echo "# setup (WORK: a new temporary directory)"
    setup echo
    for i in 1 2 3 4; do
        workload $i
        echo "# $name: $RUNS runs of each"
        for b in cpu gpu; do
            echo "$BTFCAR $args $W/$b-$out $(backend_args $b)"
        done
    done
    exit 0
fi

# ------------------------------------------------------------ the device

# "index|type|usable|name" per device of info --devices --json (one object
# a line).
device_rows() {
    "$BTFCAR" info --devices --json 2>/dev/null |
        sed -n 's/.*"index": \([0-9]*\), "type": "\([^"]*\)", "vulkan": "\([^"]*\)".*"usable": \([a-z]*\), "name": "\(.*\)"}.*/\1|\2|\4|\5 (\2, Vulkan \3)/p'
}

rank() {
    case "$1" in
    "discrete GPU") echo 5 ;;
    "integrated GPU") echo 4 ;;
    "virtual GPU") echo 3 ;;
    CPU) [ "$allow_cpu" = 1 ] && echo 2 || echo 0 ;;
    *) echo 1 ;;
    esac
}

[ -x "$BTFCAR" ] || { echo "gpu-check: $BTFCAR not found (make, or set BTF_CLI)" >&2; exit 1; }
rows=$(device_rows)
device=""
best=0
described=""
listed=""
while IFS='|' read -r idx type usable desc; do
    [ -n "$idx" ] || continue
    listed="${listed:+$listed; }$idx: $desc"
    r=$(rank "$type")
    if [ "$usable" = true ] && [ "$r" -gt "$best" ]; then
        best=$r device=$idx described=$desc is_cpu=$([ "$type" = CPU ] && echo 1 || echo 0)
    fi
done <<EOF
$rows
EOF
if [ -z "$device" ]; then
    echo "no real GPU reachable: ${listed:-no Vulkan device}"
    exit 0
fi

W=$(mktemp -d) || exit 1
pids=""
trap 'rm -rf "$W"' EXIT
trap '[ -n "$pids" ] && kill $pids 2>/dev/null; exit 130' INT TERM
started=$(date +%s)
status=0
cpu_name=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo 2>/dev/null | head -1)
head="GPU: device $device, $described"
[ "$is_cpu" = 1 ] && head="$head [--allow-cpu: a CPU driver, not a GPU]"
head="$head; CPU: ${cpu_name:-unknown} x $(nproc) cores; $("$BTFCAR" --version)"

# ------------------------------------------- 1. parity tests, and the setup

# The test programs and the setup are not timed, so they run side by side
# (most of a test's time on lavapipe is the validation layer, one thread);
# the timed runs below have the machine to themselves.
cli_abs=$(cd "$(dirname "$BTFCAR")" && pwd)/$(basename "$BTFCAR")
echo "gpu-check: $PARITY, and the material and its models ..." >&2
for t in $PARITY; do
    (
        BTF_CLI=$cli_abs BTF_CHECK_PAGE=${BTF_CHECK_PAGE:-} "$TESTS/$t" >"$W/$t.log" 2>&1
        echo $? >"$W/$t.rc"
    ) &
    pids="$pids $!"
done

# quietly COMMAND...: runs it, its output kept for the error.
# shellcheck disable=SC2317 # called through setup's RUNNER
quietly() {
    "$@" >"$W/setup.out" 2>&1 && return
    echo "gpu-check: $*: $(tail -n 1 "$W/setup.out")" >&2
    return 1
}
setup quietly || status=1
wait
pids=""

# "N/M" for a cmocka program's log: passed of run (a crash counts as one
# failure, as tests/unit/run.sh counts it).
tally() {
    ran=$(sed -n 's/^\[==========\] \([0-9]*\) test(s) run\./\1/p' "$1" | awk '{s+=$1} END {print s+0}')
    bad=$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test(s), listed below:/\1/p' "$1" | awk '{s+=$1} END {print s+0}')
    [ "$2" -ne 0 ] && [ "$bad" -eq 0 ] && bad=1
    echo "$((ran - bad))/$ran"
}

tests_line=""
for t in $PARITY; do
    rc=$(cat "$W/$t.rc" 2>/dev/null || echo 1)
    tests_line="$tests_line, $t $(tally "$W/$t.log" "$rc")"
    if [ "$rc" -ne 0 ]; then
        status=1
        echo "gpu-check: $t failed (exit $rc); its last lines:" >&2
        tail -n 15 "$W/$t.log" >&2
    fi
done
if [ "$status" -ne 0 ] && [ ! -f "$W/rf.btfcar" ]; then
    echo "parity tests (validation layer on): ${tests_line#, }"
    exit 1 # the setup failed: nothing to time
fi

# ------------------------------------------------------------ 2. timings

prepared=$(date +%s)
# timed ARGS OUT BACKEND: the median wall time of RUNS runs (seconds), or
# "failed"; the last run's output stays in $W/BACKEND-OUT.
timed() {
    times=""
    for _ in $(seq "$RUNS"); do
        rm -rf "$W/$3-$2"
        t0=$(date +%s%N)
        # shellcheck disable=SC2046,SC2086 # ARGS and the backend's are word lists
        "$BTFCAR" $1 "$W/$3-$2" $(backend_args "$3") >"$W/run.out" 2>&1 || {
            echo "gpu-check: btfcar $1 $W/$3-$2 $(backend_args "$3"): $(tail -n 1 "$W/run.out")" >&2
            echo failed
            return
        }
        t1=$(date +%s%N)
        times="$times $(echo "$t0 $t1" | awk '{printf "%.2f", ($2 - $1) / 1e9}')"
    done
    echo "$times" | tr ' ' '\n' | sed '/^$/d' | sort -n | sed -n "$(((RUNS + 1) / 2))p"
}

# same OUT: "yes", "no", or for a directory "yes (N files)" / "no (K of N
# files differ)".
same() {
    a=$W/cpu-$1 b=$W/gpu-$1
    if [ -d "$a" ]; then
        n=0 k=0
        for f in "$a"/*; do
            n=$((n + 1))
            cmp -s "$f" "$b/$(basename "$f")" || k=$((k + 1))
        done
        [ "$(find "$a" -type f | wc -l)" -eq "$(find "$b" -type f | wc -l)" ] || k=$((k + 1))
        [ "$k" -eq 0 ] && echo "yes ($n files)" || echo "no ($k of $n files differ)"
    elif [ -f "$a" ] && [ -f "$b" ]; then
        cmp -s "$a" "$b" && echo yes || echo no
    else
        echo "-"
    fi
}

row() {
    printf '| %-42s | %7s | %7s | %8s | %-16s |\n' "$1" "$2" "$3" "$4" "$5"
}

table=$(
    row workload "CPU s" "GPU s" speed-up "bytes equal"
    row "------------------------------------------" "------:" "------:" "-------:" "----------------"
    for i in 1 2 3 4; do
        workload $i
        echo "gpu-check: $name ..." >&2
        c=$(timed "$args" "$out" cpu)
        g=$(timed "$args" "$out" gpu)
        up=$(echo "$c $g" | awk '$1 + 0 > 0 && $2 + 0 > 0 {printf "%.2fx", $1 / $2; next} {print "-"}')
        row "$name" "$c" "$g" "$up" "$(same "$out")"
    done
)
echo "$head"
echo "parity tests (validation layer on): ${tests_line#, }"
echo "$table"
now=$(date +%s)
echo "times: median of $RUNS runs of the whole command (wall clock); this check took $((now - started)) s" \
    "($((prepared - started)) s tests and setup, $((now - prepared)) s timings)"
case "$table" in
*failed*) status=1 ;;
esac
if [ "$is_cpu" = 1 ] && echo "$table" | grep -q '| no'; then
    echo "gpu-check: a CPU device must give the CPU's bytes" >&2
    status=1
fi
exit $status
