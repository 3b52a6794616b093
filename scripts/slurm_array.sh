#!/usr/bin/env bash
# Run one spec across a SLURM job array: task I of N runs the I-th deterministic slice of the
# cells (`somnurbs run --shard I/N`), and a last job, started when every task has finished,
# merges the shard folders into one folder with the tables and REPORT.md (identical, timing
# aside, to a run on one machine). Submit from the repository root:
#
#   scripts/slurm_array.sh experiments/ch6_same.toml 16            # 16 tasks, full protocol
#   PROFILE=quick scripts/slurm_array.sh experiments/ch6_same.toml 4
#
# Environment: PROFILE (a spec profile, optional), OUT (default results/<spec>_slurm),
# SOMNURBS_DATA (folder with the data files), CPUS (cores per task, default 4),
# TIME (per task, default 01:00:00), SBATCH_ARGS (extra sbatch options: partition, account).
# An interrupted task is resumed by re-submitting the same command: every task runs with
# --resume, so it keeps the cells its folder already logged.
set -euo pipefail
spec="${1:?usage: scripts/slurm_array.sh SPEC.toml N}"
n="${2:?usage: scripts/slurm_array.sh SPEC.toml N}"
name="$(basename "$spec" .toml)"
out="${OUT:-results/${name}_slurm}"
cpus="${CPUS:-4}"
profile_args=()
[ -n "${PROFILE:-}" ] && profile_args=(--profile "$PROFILE")
cargo build --release --quiet
bin="$PWD/target/release/somnurbs"
mkdir -p "$out/logs"
array_id=$(sbatch --parsable ${SBATCH_ARGS:-} --job-name "somnurbs-$name" --array "1-$n" \
  --cpus-per-task "$cpus" --time "${TIME:-01:00:00}" --output "$out/logs/shard_%a.log" \
  --wrap "$bin run '$spec' ${profile_args[*]:-} --shard \$SLURM_ARRAY_TASK_ID/$n --resume --jobs $cpus --out '$out/shard_'\$SLURM_ARRAY_TASK_ID")
shards=$(for i in $(seq 1 "$n"); do printf "'%s/shard_%d' " "$out" "$i"; done)
merge_id=$(sbatch --parsable ${SBATCH_ARGS:-} --job-name "somnurbs-$name-merge" --dependency "afterok:$array_id" \
  --cpus-per-task "$cpus" --time "00:30:00" --output "$out/logs/merge.log" \
  --wrap "$bin merge $shards --jobs $cpus --out '$out/merged'")
echo "submitted array $array_id ($n shards) and merge $merge_id; results in $out/merged"
