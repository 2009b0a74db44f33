#!/usr/bin/env bash
# Throughput of `armsim study` on this machine (issue 13): one study (SUBJECTS subjects x the thesis
# protocol x 2 % noise x {thesis, synergist}) run with threads and with MPI ranks. Prints a Markdown
# table: wall time inside the run ("computed in") and of the whole command (MPI start-up included),
# tasks/s, and parallel efficiency against one worker, T1 / (workers x Tn), workers = ranks x threads
# (at most the cores). Results are checked byte-identical across the runs.
# Usage: scripts/benchmark-study-scaling.sh [build dir] [subjects]
set -euo pipefail
build=${1:-build}
subjects=${2:-24}
armsim=$(realpath "$build/armsim")
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cat > "$dir/study.yaml" <<YAML
kind: study
name: scaling
subjects: $subjects
seed: 1
protocols: [thesis]
noise_levels: [0.02]
methods:
  - {method: thesis}
  - {method: synergist}
YAML
mpirun=(mpirun --oversubscribe)
[ "$(id -u)" -eq 0 ] && mpirun+=(--allow-run-as-root)
cores=$(nproc)
echo "| run | workers | wall in run (s) | wall of command (s) | tasks/s | efficiency |"
echo "|---|---|---|---|---|---|"
t1=""
run() {  # label ranks threads command...
  local label=$1 ranks=$2 threads=$3; shift 3
  local out="$dir/out_${ranks}_${threads}_$RANDOM"
  local start end log
  start=$(date +%s.%N)
  log=$("$@" study "$dir/study.yaml" --threads "$threads" --quiet --out "$out")
  end=$(date +%s.%N)
  local inrun tasks
  inrun=$(grep -o 'computed in [0-9.]* s' <<<"$log" | awk '{print $3}')
  tasks=$(grep -o '^study .*: [0-9]* tasks' <<<"$log" | grep -o '[0-9]* tasks' | awk '{print $1}')
  [ -z "$t1" ] && t1=$inrun
  local workers=$((ranks * threads)); [ $workers -gt $cores ] && workers=$cores
  if [ -f "$dir/reference.csv" ]; then cmp -s "$out/results.csv" "$dir/reference.csv" || { echo "results differ: $label" >&2; exit 1; }
  else cp "$out/results.csv" "$dir/reference.csv"; fi
  awk -v l="$label" -v w="$workers" -v r="$inrun" -v s0="$start" -v s1="$end" -v n="$tasks" -v t1="$t1" \
    'BEGIN { printf "| %s | %d | %.2f | %.2f | %.2f | %.0f %% |\n", l, w, r, s1 - s0, n / r, 100 * t1 / (w * r) }'
}
run "1 thread" 1 1 "$armsim"
run "2 threads" 1 2 "$armsim"
run "mpirun -n 1, 1 thread" 1 1 "${mpirun[@]}" -n 1 "$armsim"
run "mpirun -n 2, 1 thread each" 2 1 "${mpirun[@]}" -n 2 "$armsim"
run "mpirun -n 2, 2 threads each (4 workers on $cores cores)" 2 2 "${mpirun[@]}" -n 2 "$armsim"
echo "results byte-identical across the runs"
