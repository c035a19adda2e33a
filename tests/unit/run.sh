#!/bin/sh
# Runs every cmocka test program given as an argument, then prints one total
# line "N passed, N failed". Exit status: 0 only if every test passed and every
# program exited cleanly (a crash counts as a failure even if cmocka missed it).
set -u
passed=0
failed=0
broken=""
for t in "$@"; do
    name=$(basename "$t")
    out=$(mktemp)
    "$t" >"$out" 2>&1
    rc=$?
    cat "$out"
    ran=$(sed -n 's/^\[==========\] \([0-9]*\) test(s) run\./\1/p' "$out" | awk '{s+=$1} END {print s+0}')
    bad=$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test(s), listed below:/\1/p' "$out" | awk '{s+=$1} END {print s+0}')
    rm -f "$out"
    if [ "$rc" -ne 0 ] && [ "$bad" -eq 0 ]; then
        # The program died or failed outside cmocka's accounting.
        bad=1
        broken="$broken $name(rc=$rc)"
    fi
    ok=$((ran - bad))
    [ "$ok" -lt 0 ] && ok=0
    passed=$((passed + ok))
    failed=$((failed + bad))
done
[ -n "$broken" ] && echo "test programs that exited abnormally:$broken"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
