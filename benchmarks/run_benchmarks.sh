#!/usr/bin/env bash
# Every figure of docs/performance.md, one benchmark after another; text and JSON go to outputs/bench/.
# THREADS=1 when another job uses the other core (run_paper.sh does), THREADS=2 on an idle 2-core machine.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p outputs/bench
T=${THREADS:-2}
export OMP_NUM_THREADS=$T
python benchmarks/bench_synth.py --stride 10 --steps 2000 --threads "$T" --json outputs/bench/synth-s10.json | tee outputs/bench/synth-s10.txt
python benchmarks/bench_scaling.py --threads "$T" --json outputs/bench/scaling.json | tee outputs/bench/scaling.txt
if [ -f outputs/random-cross/paper/seed0/train/oracle/model.pt ]; then
  python benchmarks/bench_stride.py --oracle outputs/random-cross/paper/seed0/train/oracle/model.pt --threads "$T" \
    --steps 2000 --programs 60 | tee outputs/bench/stride.txt
fi
python benchmarks/bench_synth.py --stride 1 --steps 300 --full 2 --threads "$T" --json outputs/bench/synth-s1.json | tee outputs/bench/synth-s1.txt
python benchmarks/bench_train.py --threads "$T" --json outputs/bench/train.json | tee outputs/bench/train.txt
python benchmarks/bench_cpu_kernels.py --threads "$T" --json outputs/bench/cpu-kernels.json | tee outputs/bench/cpu-kernels.txt
