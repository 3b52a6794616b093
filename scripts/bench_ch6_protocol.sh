#!/usr/bin/env bash
# The full thesis Chapter 6 protocol (ch6_same + ch6_diff: 2 grids x 5 data sets x 4
# parameterisations x 7 nets x {GA, DE, PSO} x 10 repeats = 8,400 runs of 2000 x 40), timed.
# Prints the wall time of each spec and of both, our summed CPU time, and the ratios to the
# thesis' CPU time (Appendices M and N: AVG seconds per run x 10 repeats, summed).
#
#   scripts/bench_ch6_protocol.sh [OUT_DIR] [JOBS]      (defaults: a temporary folder, nproc)
#
# With PREV_BIN=/path/to/an/older/somnurbs, each spec is also run by that build right before this
# one (back to back, so both see the same machine) and the ratio of the wall times is printed.
# The CPU model, the copy of the kernels that runs (SOMNURBS_SIMD, default auto) and the load
# before each run are printed, since a shared machine's speed varies from hour to hour.
#
# Needs the Chapter 4 maps (results/ch4_models/maps, from the README's main job); missing maps are
# recomputed (the specs set maps_missing = "recompute"). The talus mesh is read from data/ (or
# SOMNURBS_DATA), as for the main job.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-$(mktemp -d)}"
jobs="${2:-$(nproc)}"
mkdir -p "$out"
cargo build --release --quiet
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'), $(nproc) cores; flags: $(grep -m1 -o -w -E 'avx512vl|avx2' /proc/cpuinfo | sort -u | tr '\n' ' ')SOMNURBS_SIMD=${SOMNURBS_SIMD:-auto}"
wall=0
for s in ch6_same ch6_diff; do
  if [ -n "${PREV_BIN:-}" ]; then
    echo "load before the previous build's $s: $(cut -d' ' -f1-3 /proc/loadavg)"
    p0=$(date +%s.%N)
    "$PREV_BIN" run "experiments/$s.toml" --out "$out/prev_$s" --jobs "$jobs" > "$out/prev_$s.log" 2>&1
    p1=$(date +%s.%N)
    prev=$(echo "$p1 - $p0" | bc)
    echo "$s, previous build ($PREV_BIN): $prev s wall"
  fi
  echo "load before $s: $(cut -d' ' -f1-3 /proc/loadavg)"
  t0=$(date +%s.%N)
  ./target/release/somnurbs run "experiments/$s.toml" --out "$out/$s" --jobs "$jobs" > "$out/$s.log" 2>&1
  t1=$(date +%s.%N)
  this=$(echo "$t1 - $t0" | bc)
  wall=$(echo "$wall + $this" | bc)
  echo "$s: $this s wall ($(($(wc -l < "$out/$s/runs.csv") - 1)) runs, $jobs threads)"
  if [ -n "${PREV_BIN:-}" ]; then
    echo "$s: this build / previous build = $(echo "scale=3; $this / $prev" | bc)"
  fi
done
# Our CPU: the cpu_s column of every run.
ours=$(awk -F, 'FNR == 1 { for (i = 1; i <= NF; i++) if ($i == "cpu_s") c = i; next } { s += $c } END { printf "%.1f", s }' "$out/ch6_same/runs.csv" "$out/ch6_diff/runs.csv")
# The thesis' CPU: 10 repeats x the AVG columns of Appendices M and N.
thesis=$(awk -F, 'FNR == 1 { for (i = 1; i <= NF; i++) { if ($i == "ga_avg_s") g = i; if ($i == "de_avg_s") d = i; if ($i == "pso_avg_s") p = i }; next } { s += 10 * ($g + $d + $p) } END { printf "%.1f", s }' experiments/reference/appendix_m.csv experiments/reference/appendix_n.csv)
# Issue 21 part 3: 10 minutes on 2 cores of an AVX2-only machine, 6 where AVX-512 is present.
if grep -q -m1 -w avx512vl /proc/cpuinfo; then target=6; else target=10; fi
met=$(echo "$wall <= $target * 60" | bc)
echo "both: $wall s wall ($(echo "scale=2; $wall / 60" | bc) min; target $target min on $jobs threads of this CPU: $([ "$met" = 1 ] && echo met || echo not met))"
echo "CPU: ours $ours s, thesis $thesis s ($(echo "scale=1; $thesis / 3600" | bc) h)"
echo "ratio thesis CPU / our CPU: $(echo "scale=0; $thesis / $ours" | bc)x; thesis CPU / our wall: $(echo "scale=0; $thesis / $wall" | bc)x"
echo "results in $out"
