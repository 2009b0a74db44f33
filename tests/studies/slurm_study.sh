#!/usr/bin/env bash
# ctest (label slurm): submits the docs' batch scripts (scripts/slurm/*.sbatch) verbatim to a one-node
# Slurm cluster (scripts/slurm-local.sh; started here unless it runs, and then stopped) with a small
# study, and checks the job's files byte-identical to `armsim study` run directly on threads.
#   slurm_study.sh submit  SOURCE_DIR ARMSIM WORK_DIR   study.sbatch runs to the end (2 MPI ranks under srun)
#   slurm_study.sh requeue SOURCE_DIR ARMSIM WORK_DIR   study.sbatch is paused mid-study, requeued
#                                                       (`scontrol requeue`) and resumes from the journal
#   slurm_study.sh array   SOURCE_DIR ARMSIM WORK_DIR   study-array.sbatch as a 2-task job array (shards),
#                                                       then the merge job (--dependency=afterany)
# Exit 77 (ctest SKIP_RETURN_CODE) with the reason when Slurm or munge is not installed.
set -euo pipefail
mode=$1 src=$2 armsim=$3 work=$4
study=$src/tests/studies/slurm_study.yaml
tasks=16  # slurm_study.yaml: 8 subjects x 1 protocol x 1 noise level x 2 methods

for b in munged slurmctld slurmd sbatch squeue scontrol; do
    if ! command -v "$b" > /dev/null && [ ! -x "/usr/sbin/$b" ]; then
        echo "SKIP: $b is not installed (bash scripts/setup.sh --tests installs slurm-wlm and munge)"
        exit 77
    fi
done
fail() { echo "FAIL: $*" >&2; exit 1; }

rm -rf "$work"
mkdir -p "$work"
cd "$work"  # the jobs' working directory: their logs land here

cluster=$src/scripts/slurm-local.sh
# A cluster of this build's own (state folder and ports from the build folder), so two test suites on
# one machine (a fresh clone beside a sanitizer build) do not start and stop each other's cluster. The
# folder stays short: munge's socket path must fit a Unix socket name.
key=$(printf '%s' "$(dirname "$work")" | cksum | cut -d' ' -f1)
export ARMSIM_SLURM_DIR=${ARMSIM_SLURM_DIR:-/tmp/armsim-slurm-$(id -u)-$((key % 100000))}
export ARMSIM_SLURM_PORT=${ARMSIM_SLURM_PORT:-$((16817 + 2 * (key % 2000)))}
started=0
jobs=()
cleanup() {
    [ ${#jobs[@]} -gt 0 ] && scancel "${jobs[@]}" 2> /dev/null || true
    if [ $started -eq 1 ]; then bash "$cluster" stop || true; fi
}
trap cleanup EXIT
if ! bash "$cluster" status > /dev/null; then
    bash "$cluster" start
    started=1
fi
eval "$(bash "$cluster" env)"

# The reference: the same study on two threads, no Slurm.
"$armsim" study "$study" --threads 2 --quiet --out "$work/threads" > threads.log 2>&1 || { cat threads.log; fail "threaded run"; }

submit() {  # submit SCRIPT SBATCH_OPTIONS...: prints the job id
    local script=$1
    shift
    ARMSIM_STUDY=$study ARMSIM_OUT=$work/slurm ARMSIM=$armsim sbatch --parsable --time=10:00 "$@" "$src/scripts/slurm/$script"
}
if [ "$mode" = array ]; then
    # Two shards of one CPU each, then the merge on both CPUs once they have ended.
    array=$(submit study-array.sbatch --array=0-1 --ntasks=1 --cpus-per-task=1)
    jobs+=("$array")
    job=$(submit study-array.sbatch --dependency=afterany:"$array" --ntasks=1 --cpus-per-task=2)
else
    # Two ranks of one CPU each on the local node (the script's #SBATCH sizes are a real cluster's).
    job=$(submit study.sbatch --nodes=1 --ntasks=2 --ntasks-per-node=2 --cpus-per-task=1)
fi
jobs+=("$job")
echo "submitted job ${jobs[*]} ($mode)"
log=$work/armsim-study-$job.log

job_state() { scontrol show job "$job" 2> /dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | head -1; }
wait_for() {  # wait_for SECONDS WHAT PREDICATE: polls every 0.1 s
    local seconds=$1 what=$2
    shift 2
    for _ in $(seq 1 $((seconds * 10))); do
        "$@" && return 0
        sleep 0.1
    done
    echo "--- job: $(scontrol show job "$job" 2>&1 | tr '\n' ' ')"
    cat "$work"/armsim-study-*.log 2> /dev/null || true
    fail "$what: not after $seconds s"
}
journal_results() { echo $(($(cat "$work/slurm/journal.log" 2> /dev/null | wc -l) - 1)); }
has_a_group() { [ "$(journal_results)" -ge 2 ]; }
is_pending() { [ "$(job_state)" = PENDING ]; }
job_reason() { scontrol show job "$job" 2> /dev/null | sed -n 's/.*Reason=\([A-Za-z_]*\).*/\1/p' | head -1; }
# No step daemon of the job left and the node idle (sinfo says "idle" only with no job completing).
first_run_gone() {
    ! pgrep -f "slurmstepd: \[$job\." > /dev/null && [ "$(sinfo -h -o %T 2> /dev/null | head -1)" = idle ]
}
has_ended() { case "$(job_state)" in COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY) return 0 ;; esac; return 1; }

if [ "$mode" = requeue ]; then
    # Pause the job once a group is journaled, then requeue it as a preemption would. The ranks are
    # stopped here first (SIGSTOP, at once): `scontrol suspend` goes through slurmctld, and on a loaded
    # machine the study finished its last 14 tasks before that arrived. Slurm then suspends the job.
    wait_for 120 "a group in the job's journal" has_a_group
    pkill -STOP -f -- "^$armsim study $study --threads [0-9]+ --out $work/slurm" || true   # the ranks, not srun
    scontrol suspend "$job" || fail "job $job could not be paused (state $(job_state))"
    before=$(journal_results)
    [ "$before" -lt $tasks ] || fail "the job finished before it was paused ($before results)"
    scontrol requeue "$job"
    # A requeued suspended job is held, and Slurm delays any requeued job by two minutes: release it
    # and let it start now.
    wait_for 60 "the requeued job pending" is_pending
    # Start the second run only once the first run's step daemons are gone: one still cleaning up
    # removes the spool folder the second launch uses (same job id), the launch fails and Slurm holds
    # the job (launch_failed_requeued_held), which a loaded machine showed.
    wait_for 120 "the first run's processes gone" first_run_gone
    scontrol release "$job"
    scontrol update jobid="$job" starttime=now
    echo "requeued job $job after $before of $tasks results"
fi

# Slurm holds a job whose launch failed (a node-side failure, not the job's); an administrator releases
# it. Do that once, saying so, and fail on a second launch failure.
released_after_launch_failure=0
ended_or_release() {
    has_ended && return 0
    if [ "$(job_reason)" = launch_failed_requeued_held ]; then
        [ $released_after_launch_failure -eq 0 ] || fail "job $job: Slurm could not launch it twice"
        released_after_launch_failure=1
        echo "job $job: Slurm held it after a failed launch (its node, not the study); released once"
        wait_for 120 "the failed launch's processes gone" first_run_gone
        scontrol release "$job"
        scontrol update jobid="$job" starttime=now
    fi
    return 1
}
wait_for 300 "job $job finished" ended_or_release
state=$(job_state)
cat "$work"/armsim-study-*.log
[ "$state" = COMPLETED ] || fail "job $job ended $state"

case $mode in
    submit)
        grep -q "on 2 ranks x 1 thread" "$log" || fail "the job did not run 2 MPI ranks under srun" ;;
    requeue)
        grep -q "on 2 ranks x 1 thread" "$log" || fail "the job did not run 2 MPI ranks under srun"
        grep -q "run 2," "$log" || fail "the job did not run a second time"
        resumed=$(sed -n 's/.*, \([0-9]*\) resumed from the journal.*/\1/p' "$log" | tail -1)
        [ -n "$resumed" ] && [ "$resumed" -ge "$before" ] && [ "$resumed" -lt $tasks ] ||
            fail "the requeued run resumed '$resumed' results (journal held $before of $tasks)"
        echo "the requeued run resumed $resumed of $tasks results" ;;
    array)
        for shard in 0/2 1/2; do  # each shard computed its 4 groups (8 cells)
            grep -q "^shard $shard: study 'slurm': 8 tasks .* 8 computed" "$work"/armsim-study-*.log ||
                fail "shard $shard did not compute its 8 cells"
        done
        grep -q "0 computed .* $tasks resumed from the journal" "$log" || fail "the merge job computed cells"
        grep -q "2 shard journals merged into journal.log: $tasks of the resumed tasks" "$log" ||
            fail "the merge job did not merge both shards' journals" ;;
esac

files=(results.csv summary.csv study.yaml)
for f in "$work"/threads/*.png; do files+=("$(basename "$f")"); done
[ ${#files[@]} -gt 3 ] || fail "the threaded run wrote no plot"
for f in "${files[@]}"; do
    cmp "$work/threads/$f" "$work/slurm/$f" || fail "$f differs from the threaded run's"
done
echo "PASS: $mode: ${files[*]} byte-identical to the threaded run"
