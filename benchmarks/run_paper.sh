#!/usr/bin/env bash
# The paper's full protocol (budget=paper) on its three tasks, two pipelines at a time on a 2-core machine:
# each pipeline runs on one torch thread (these small models are launch-bound, so two one-thread processes
# get nearly twice the throughput of one two-thread process). Logs and /usr/bin/time summaries go to
# outputs/logs/; every stage resumes where it stopped if the script is run again.
#
#   bash benchmarks/run_paper.sh            # all three tasks
#   bash benchmarks/run_paper.sh random-grid  # one task
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p outputs/logs
export OMP_NUM_THREADS=1
run() {  # one task's pipeline, timed
  local task=$1
  local start=$(date +%s)
  neurosym pipeline task="$task" budget=paper threads=1 > "outputs/logs/$task.log" 2>&1
  echo "$task: $(( $(date +%s) - start )) s" | tee -a outputs/logs/wall.txt
}
if [ $# -gt 0 ]; then
  for t in "$@"; do run "$t"; done
  exit 0
fi
start=$(date +%s)
( run random-cross; run unlabeled-goals ) &
run random-grid &
wait
echo "all three tasks: $(( $(date +%s) - start )) s" | tee -a outputs/logs/wall.txt
