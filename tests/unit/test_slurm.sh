#!/bin/sh
# test_slurm.sh — a sweep split over a real Slurm cluster of one node
# (docs/cluster.md): munged, slurmctld and slurmd started here on
# loopback from a slurm.conf written into a temporary folder, the sweep of a
# generated material submitted as a 4-task job array
# (examples/slurm/sweep-share.sbatch) and merged by a job that waits for it
# (--dependency=afterok, examples/slurm/sweep-merge.sbatch); checked: the
# merged report.json equals a one-process report point for point (all but
# the times), a share cancelled mid-run (scancel) leaves its point missing,
# the merge names it, resubmitting that one array index completes the sweep;
# nothing is left running; a library run of three generated materials
# (examples/slurm/library-task.sbatch, library-merge.sbatch) gives one
# library page with their figures. Skipped, saying so, only where slurm-wlm or munge
# is not installed (make deps installs them). Needs root (the daemons).
# Usage: BTF_CLI=build/btfcar sh tests/unit/test_slurm.sh
set -u
CLI=${BTF_CLI:-build/btfcar}
case $CLI in /*) ;; *) CLI=$(pwd)/$CLI ;; esac
HERE=$(cd "$(dirname "$0")/../.." && pwd)
passed=0
failed=0
ok() { passed=$((passed + 1)); echo "ok: $1"; }
bad() { failed=$((failed + 1)); echo "FAILED: $1"; }
summary() { echo "test_slurm: $passed passed, $failed failed"; }

for b in slurmctld slurmd sbatch squeue scancel munged; do
    if ! command -v "$b" >/dev/null 2>&1 && [ ! -x "/usr/sbin/$b" ]; then
        echo "test_slurm: SKIPPED: $b is not installed (make deps installs slurm-wlm and munge)"
        summary
        exit 0
    fi
done
if [ "$(id -u)" -ne 0 ]; then
    echo "test_slurm: SKIPPED: the Slurm daemons need root"
    summary
    exit 0
fi

T=$(mktemp -d /tmp/btfcar-slurm-XXXXXX)
PORT=$((17000 + ($$ % 400) * 2))
HOST=$(hostname -s)
MUNGE_PID=""
cleanup() {
    for f in "$T/slurmd.pid" "$T/slurmctld.pid"; do
        [ -f "$f" ] && kill "$(cat "$f")" 2>/dev/null
    done
    [ -n "$MUNGE_PID" ] && kill "$MUNGE_PID" 2>/dev/null
    sleep 1
    rm -rf "$T"
}
trap cleanup EXIT INT TERM

mkdir -p "$T/state" "$T/spool"
MEM_MB=$(($(sed -n 's/^MemTotal: *\([0-9]*\) kB/\1/p' /proc/meminfo) / 1024))
cat >"$T/slurm.conf" <<EOF
ClusterName=btfcartest
SlurmctldHost=$HOST(127.0.0.1)
SlurmUser=root
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
AuthType=auth/munge
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$MEM_MB State=UNKNOWN
PartitionName=test Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$T/slurm.conf"

# munged: the running one, else one of ours (the package made the key).
if ! pgrep -x munged >/dev/null 2>&1; then
    mkdir -p /run/munge && chown munge:munge /run/munge 2>/dev/null
    su -s /bin/sh munge -c /usr/sbin/munged || { bad "munged does not start"; summary; exit 1; }
    for i in $(seq 1 20); do # the daemon's pid, once written
        [ -s /run/munge/munged.pid ] && MUNGE_PID=$(cat /run/munge/munged.pid) && break
        sleep 0.5
    done
fi
PATH=$PATH:/usr/sbin
slurmctld -f "$SLURM_CONF" && slurmd -f "$SLURM_CONF" || { bad "the daemons do not start"; summary; exit 1; }
up=0
for i in $(seq 1 60); do
    if sinfo -h -o %t 2>/dev/null | grep -q idle; then up=1; break; fi
    sleep 1
done
[ $up = 1 ] && ok "a one-node cluster is up (sinfo: idle)" || {
    bad "the node never became idle: $(tail -3 "$T/slurmctld.log")"; summary; exit 1; }

# waits until job $1 (and its array elements) left the queue, at most $2 s
wait_job() {
    for i in $(seq 1 "$2"); do
        [ -z "$(squeue -h -j "$1" 2>/dev/null)" ] && return 0
        sleep 1
    done
    return 1
}
# the sweep's points in a report.json without the measured times (and the
# time front, which follows them)
points() {
    sed -n '/"points"/,/^\t\t\]/p' "$1" | grep -v -E 'seconds|pareto_time|resumed'
}

cd "$T"
"$CLI" generate -q --material leather --size 32 --seed 2 ds && "$CLI" analyse -q ds -o m.btfcar ||
    { bad "generate and analyse"; summary; exit 1; }
export GRID="--sweep --sweep-subspaces auto,2 --sweep-levels 1 --sweep-neighbours auto,4 --sweep-seeds 1 --views 2 --lights 2"
export DATASET="$T/ds" MODEL="$T/m.btfcar" SHARES=4 BTFCAR="$CLI"
# shellcheck disable=SC2086
"$CLI" report -q ds m.btfcar $GRID -o one || bad "the one-process report"

# the 4 shares and the merge
export OUT="$T/split"
J=$(sbatch --parsable --array=0-3 --cpus-per-task=1 --mem=1G -D "$T" "$HERE/examples/slurm/sweep-share.sbatch")
M=$(sbatch --parsable --mem=1G --dependency=afterok:"$J" -D "$T" "$HERE/examples/slurm/sweep-merge.sbatch")
if wait_job "$J" 300 && wait_job "$M" 120 && [ -f split/report.json ]; then
    ok "4 array tasks and the merge after them ran (jobs $J, $M)"
else
    bad "the array job or the merge did not finish: $(cat btfcar-*.out 2>/dev/null | tail -3)"
fi
if [ -f split/report.json ] && points one/report.json >a.txt && points split/report.json >b.txt &&
    [ -s a.txt ] && cmp -s a.txt b.txt; then
    ok "the merged report equals the one-process report point for point ($(grep -c '"bytes"' a.txt) points)"
else
    bad "the merged report differs from the one-process report"
fi

# a share cancelled: its point missing, the merge names it, the one index rerun
export OUT="$T/cancelled"
J=$(sbatch --parsable --array=0-3 --cpus-per-task=1 --mem=1G -D "$T" "$HERE/examples/slurm/sweep-share.sbatch")
scancel "${J}_2"
# The other three tasks must have ended before the folder is counted: a task
# still queued or running on a loaded machine is not a missing point. When
# the wait runs out, say so and show the tasks' own output.
if ! wait_job "$J" 600; then
    bad "array job $J still in the queue after 600 s: $(squeue -h -j "$J" 2>&1 | tr '\n' ' ')"
elif [ ! -f cancelled/sweep/point-K2-L1-N0.json ] && [ "$(ls cancelled/sweep | wc -l)" = 3 ]; then
    ok "scancel of array task 2: its point is missing, the other 3 are there"
else
    bad "after scancel of task 2: $(ls cancelled/sweep 2>&1 | tr '\n' ' ')| tasks' output: $(tail -n 2 btfcar-sweep-"$J"_*.out 2>&1 | tr '\n' ' ')"
fi
M=$(sbatch --parsable --mem=1G -D "$T" "$HERE/examples/slurm/sweep-merge.sbatch")
wait_job "$M" 120
if grep -q "1 of the sweep's 4 points are missing: #2 (K 2, levels 1, neighbours 0)" "btfcar-merge-$M.out"; then
    ok "the merge fails naming the missing point"
else
    bad "the merge's message: $(cat "btfcar-merge-$M.out")"
fi
J2=$(sbatch --parsable --array=2 --cpus-per-task=1 --mem=1G -D "$T" "$HERE/examples/slurm/sweep-share.sbatch")
M=$(sbatch --parsable --mem=1G --dependency=afterok:"$J2" -D "$T" "$HERE/examples/slurm/sweep-merge.sbatch")
wait_job "$J2" 300 && wait_job "$M" 120
if [ -f cancelled/report.json ] && points cancelled/report.json >c.txt && cmp -s a.txt c.txt; then
    ok "resubmitting array index 2 alone completes the sweep: the one-process points"
else
    bad "the resubmitted share did not complete the sweep: $(tail -2 "btfcar-merge-$M.out")"
fi

# the library run: three generated materials, one array task each, then the page
for mat in leather fabric wood; do
    "$CLI" generate -q --material $mat --size 32 --seed 3 "lib-$mat" || bad "generate $mat"
    echo "$T/lib-$mat" >>materials.txt
done
export LIST="$T/materials.txt" OUT="$T/library" REPORT_OPTS="--views 2 --lights 2"
J=$(sbatch --parsable --array=0-2 --cpus-per-task=1 --mem=1G -D "$T" "$HERE/examples/slurm/library-task.sbatch")
M=$(sbatch --parsable --mem=500M --dependency=afterok:"$J" -D "$T" "$HERE/examples/slurm/library-merge.sbatch")
wait_job "$J" 300 && wait_job "$M" 120
rows=$(grep -c '"mean_combined"' library/library/library.json 2>/dev/null)
if [ "$rows" = 3 ] && grep -q 'lib-fabric/report/index.html' library/library/index.html &&
    grep -q "$(sed -n 's/.*"mean_combined":\t*\([0-9.]*\).*/\1/p' library/lib-wood/report/report.json | head -1)" \
        library/library/library.json; then
    ok "the library run: 3 materials as 3 array tasks, one library page with their reports' figures"
else
    bad "the library run: $rows rows; $(tail -2 btfcar-library-$M.out 2>/dev/null)"
fi

[ -z "$(squeue -h 2>/dev/null)" ] && ok "no job left in the queue" || bad "jobs left: $(squeue -h)"
cd /
for f in "$T/slurmd.pid" "$T/slurmctld.pid"; do
    [ -f "$f" ] && kill "$(cat "$f")" 2>/dev/null
done
sleep 2
if ! pgrep -f "slurm.*-f $T/slurm.conf" >/dev/null 2>&1 && ! pgrep -x slurmstepd >/dev/null 2>&1; then
    ok "the daemons stopped by their pids, no slurmstepd left"
else
    bad "processes left: $(pgrep -a -f "slurm" | head -3)"
fi
summary
[ "$failed" = 0 ]
