#!/usr/bin/env bash
# Each Chapter 6 optimiser's cost per evaluation beyond the fitness, in instructions (callgrind
# counts them exactly, whatever else runs on the machine): on the 18x18 net of the 20x20 DNSOM map
# of the spindle (benches/optim.rs), N = 40 (1 + G) fitness evaluations, then one run of each
# optimiser (G generations of 40; GA, DE, PSO make 40 (1 + G) evaluations, CSA and ICSA
# 40 (1 + 2 G)). Prints instructions per evaluation and
#   overhead / fitness = (run instructions / run evaluations - fitness instructions / N)
#                        / (fitness instructions / N).
#
#   scripts/count_overhead.sh [G] [OPTIMISERS...]     (defaults: 100; ga de pso csa icsa)
#
# SOMNURBS_SIMD picks the kernels' copy as for any run (default: the fastest this CPU has).
set -euo pipefail
cd "$(dirname "$0")/.."
g="${1:-100}"
shift || true
if [ $# -eq 0 ]; then opts=(ga de pso csa icsa); else opts=("$@"); fi
CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}" cargo bench --bench optim --no-run --quiet 2>/dev/null
bin=$(ls -t target/release/deps/optim-* | grep -v '\.d$' | head -1)
tmp=$(mktemp -d)
count() {
  BENCH_COUNT="$1" BENCH_GENERATIONS="$g" valgrind --tool=callgrind --toggle-collect='*counted*' \
    --callgrind-out-file="$tmp/$1.out" "$bin" > "$tmp/$1.log" 2>&1
  local ir evals
  ir=$(grep -m1 '^summary:' "$tmp/$1.out" | awk '{print $2}')
  evals=$(grep -m1 '^BENCH_COUNT' "$tmp/$1.log" | awk '{print $3}')
  echo "$ir $evals"
}
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'); SOMNURBS_SIMD=${SOMNURBS_SIMD:-auto}; G = $g"
read -r fir fev < <(count fitness)
fper=$(echo "scale=1; $fir / $fev" | bc)
echo "fitness: $fir instructions / $fev evaluations = $fper per evaluation"
for o in "${opts[@]}"; do
  read -r ir ev < <(count "$o")
  per=$(echo "scale=1; $ir / $ev" | bc)
  ratio=$(echo "scale=3; ($per - $fper) / $fper" | bc)
  echo "$o: $ir instructions / $ev evaluations = $per per evaluation; overhead $ratio x the fitness"
done
rm -rf "$tmp"
