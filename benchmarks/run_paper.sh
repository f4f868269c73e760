#!/usr/bin/env bash
# The paper's full protocol on its three tasks: kept for old instructions; benchmarks/run_paper.py does the work
# (all stages of the three tasks as one dependency graph on 2 one-thread workers; see its docstring).
#
#   bash benchmarks/run_paper.sh                 # all three tasks
#   bash benchmarks/run_paper.sh random-grid     # one task
#   bash benchmarks/run_paper.sh --followups     # then the follow-up searches of docs/results.md
set -euo pipefail
cd "$(dirname "$0")/.."
exec python benchmarks/run_paper.py "$@"
