#!/bin/sh
# Runs libFuzzer targets:  sh tests/fuzz/fuzz.sh SECONDS BINARY...  (from the
# repository root; `make fuzz` builds the binaries and calls this).
#
# Each BINARY (e.g. build-fuzz/fuzz_model) runs for SECONDS with a work
# corpus beside it (build-fuzz/corpus/NAME: new interesting inputs collect
# there, the committed seeds are never modified) seeded from
# tests/fuzz/corpus/NAME/ when that folder exists. A crash, leak, sanitizer
# report or timeout stops that target; its input is saved as
# build-fuzz/crashes/NAME-crash-... and the script exits 1 after running the
# rest. The last lines of each run's log are printed; the whole log is in
# build-fuzz/NAME.log. Reproduce a crash with:  BINARY CRASH-FILE
set -u
if [ $# -lt 1 ]; then
    echo "usage: sh tests/fuzz/fuzz.sh SECONDS BINARY..." >&2
    exit 2
fi
secs=$1
shift
if [ $# -eq 0 ]; then
    echo "fuzz: no targets (tests/fuzz/fuzz_*.c)"
    exit 0
fi
failed=""
for bin in "$@"; do
    name=$(basename "$bin")
    out=$(dirname "$bin")
    work="$out/corpus/$name"
    crashes="$out/crashes"
    log="$out/$name.log"
    mkdir -p "$work" "$crashes"
    seeds=""
    [ -d "tests/fuzz/corpus/$name" ] && seeds="tests/fuzz/corpus/$name"
    echo "== $name: ${secs}s, corpus $work${seeds:+ + $seeds}"
    # shellcheck disable=SC2086
    "$bin" -max_total_time="$secs" -timeout=30 -rss_limit_mb=2048 -print_final_stats=1 \
        -artifact_prefix="$crashes/$name-" "$work" $seeds >"$log" 2>&1
    rc=$?
    if [ "$rc" -eq 0 ]; then
        grep -E "^(#[0-9]+.*DONE|stat::number_of_executed_units|stat::peak_rss_mb)" "$log" | tail -n 3
    else
        echo "fuzz: $name FAILED (exit $rc); log: $log"
        tail -n 40 "$log"
        failed="$failed $name"
    fi
done
if [ -n "$failed" ]; then
    echo "fuzz: failing targets:$failed"
    exit 1
fi
echo "fuzz: every target ran ${secs}s without a crash"
