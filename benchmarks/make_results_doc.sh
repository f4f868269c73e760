#!/usr/bin/env bash
# docs/results.md = docs/results_header.md + docs/results_glance.md (hand-written) + the generated sections of
# results_tables.py (tables, figures, programs, stage times, claim verdicts) + docs/results_analysis.md.
set -euo pipefail
cd "$(dirname "$0")/.."
{
cat docs/results_header.md
echo
cat docs/results_glance.md
echo
python benchmarks/results_tables.py --figures docs/figures
python benchmarks/results_tables.py --tasks random-grid --lam 0.2
if ls outputs/unlabeled-goals/paper/seed0/eval/prog-retrained-*-hinge >/dev/null 2>&1; then
  python benchmarks/results_tables.py --tasks unlabeled-goals --objective hinge
fi
cat docs/results_analysis.md
} > docs/results.md
