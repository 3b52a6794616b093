#!/usr/bin/env bash
# Run one spec across a SLURM job array: task I of N runs the I-th deterministic slice of the
# cells (`somnurbs run --shard I/N`) into its own folder OUT/shard_I, and a last job, started when
# every task has ended, merges the shard folders into OUT/merged with the tables and REPORT.md
# (identical, timing aside, to a run on one machine). Submit from the repository root:
#
#   scripts/slurm_array.sh experiments/ch6_same.toml 16            # 16 tasks, full protocol
#   scripts/slurm_array.sh experiments/ch6_same.toml 4 --profile quick
#   scripts/slurm_array.sh --status results/ch6_same_slurm         # progress of a submitted array
#
# Arguments after N are passed to every `somnurbs run` (e.g. --profile, --data-dir); they are
# checked with `somnurbs run --dry-run` before anything is submitted.
# Environment: PROFILE (a spec profile, optional), OUT (default results/<spec>_slurm),
# SOMNURBS_DATA (folder with the data files), PARTITION (default: the cluster's default partition),
# CPUS (cores per task; default 4, or fewer when the partition's largest node has fewer; a request
# no node of the partition can hold is refused here instead of pending forever),
# TIME (per task, default 01:00:00), SBATCH_ARGS (extra sbatch options, e.g. an account),
# SOMNURBS_BIN (a built somnurbs binary to use instead of `cargo build --release` here).
# An interrupted task is resumed by re-submitting the same command: every task runs with
# --resume, so it keeps the cells its folder already logged. Each task writes OUT/slurm/status/
# shard_I ("exit CODE" when it ends); the merge job runs after every task (afterany) and, when a
# task failed or was killed, fails naming it instead of waiting forever. A submission is refused
# while jobs of an earlier one for the same OUT are still queued or running.
set -euo pipefail
usage="usage: scripts/slurm_array.sh SPEC.toml N [somnurbs run args...] | scripts/slurm_array.sh --status OUT"
die() { echo "slurm_array: error: $*" >&2; exit 2; }

# Queued or running jobs among the ids saved in OUT/slurm/jobs (one line each: "JOBID STATE").
live_jobs() {
  local ids
  ids="$(awk '{print $2}' "$1/slurm/jobs" 2>/dev/null | paste -sd, -)"
  [ -n "$ids" ] || return 0
  squeue -h -j "$ids" -o '%i %T' 2>/dev/null || true
}

# --status OUT: one line per shard and for the merge; exit 0 when merged, 1 when failed, 3 while
# jobs are queued or running.
status() {
  local out="$1" n f s cells live
  [ -r "$out/slurm/jobs" ] || die "$out/slurm/jobs not found: no array was submitted with OUT=$out"
  n="$(cat "$out/slurm/shards")"
  live="$(live_jobs "$out")"
  echo "jobs: $(awk '{printf "%s %s  ", $1, $2}' "$out/slurm/jobs")"
  [ -z "$live" ] || { echo "queued or running:"; echo "$live" | sed 's/^/  /'; }
  for i in $(seq 1 "$n"); do
    f="$out/slurm/status/shard_$i"
    s="$(cat "$f" 2>/dev/null || echo "not started")"
    cells=0
    [ -r "$out/shard_$i/cells.jsonl" ] && cells="$(wc -l <"$out/shard_$i/cells.jsonl")"
    echo "shard $i/$n: $s, $cells cells logged (log $out/logs/shard_$i.log)"
  done
  s="$(cat "$out/slurm/status/merge" 2>/dev/null || echo "not started")"
  echo "merge: $s (log $out/logs/merge.log)"
  case "$s" in
    "exit 0") echo "results: $out/merged"; return 0 ;;
    exit*|failed*) return 1 ;;
  esac
  [ -n "$live" ] && return 3
  echo "merge: no job queued or running and no result: cancelled or killed?"
  return 1
}

if [ "${1:-}" = "--status" ]; then
  status "${2:?$usage}"
  exit $?
fi

spec="${1:?$usage}"
n="${2:?$usage}"
shift 2
run_args=("$@")
[[ "$n" =~ ^[1-9][0-9]*$ ]] || die "N must be a positive whole number, not '$n'"
[ -r "$spec" ] || die "spec $spec not found (submit from the repository root)"
for a in "${run_args[@]}"; do
  case "$a" in
    --out|--out=*|--shard|--shard=*|--jobs|--jobs=*|--resume) die "$a is set by the script (use OUT=... and CPUS=...)" ;;
  esac
done
[ -n "${PROFILE:-}" ] && run_args=(--profile "$PROFILE" "${run_args[@]}")
name="$(basename "$spec" .toml)"
out="${OUT:-results/${name}_slurm}"
out="$(realpath -m "$out")"
workdir="$PWD"

if [ -n "${SOMNURBS_BIN:-}" ]; then
  bin="$(cd "$(dirname "$SOMNURBS_BIN")" && pwd)/$(basename "$SOMNURBS_BIN")"
  [ -x "$bin" ] || die "SOMNURBS_BIN=$SOMNURBS_BIN is not an executable"
else
  cargo build --release --quiet
  bin="$PWD/target/release/somnurbs"
fi
data=""
if [ -n "${SOMNURBS_DATA:-}" ]; then
  [ -d "$SOMNURBS_DATA" ] || die "SOMNURBS_DATA=$SOMNURBS_DATA is not a folder"
  data="$(cd "$SOMNURBS_DATA" && pwd)"
fi

# A spec, profile or argument error shows here, once, not in every task.
cells="$(SOMNURBS_DATA="$data" "$bin" run "$spec" "${run_args[@]}" --dry-run | wc -l)" || die "somnurbs run $spec ${run_args[*]} --dry-run failed (see above)"

# The partition: PARTITION, else SBATCH_PARTITION, else -p/--partition in SBATCH_ARGS, else the default.
partition="${PARTITION:-${SBATCH_PARTITION:-}}"
if [ -z "$partition" ]; then
  read -r -a sargs <<<"${SBATCH_ARGS:-}"
  for ((k = 0; k < ${#sargs[@]}; k++)); do
    case "${sargs[k]}" in
      -p|--partition) partition="${sargs[k + 1]:-}" ;;
      --partition=*) partition="${sargs[k]#--partition=}" ;;
      -p?*) partition="${sargs[k]#-p}" ;;
    esac
  done
fi
# CPUs of the partition's largest node (sinfo marks the default partition with a '*').
if [ -n "$partition" ]; then
  node_cpus="$(sinfo -h -N -p "$partition" -o '%c' 2>/dev/null | sort -n | tail -n 1)" || true
else
  node_cpus="$(sinfo -h -N -o '%c %P' 2>/dev/null | awk '$2 ~ /\*$/ {print $1}' | sort -n | tail -n 1)" || true
fi
where="partition ${partition:-(default)}"
[ -n "$node_cpus" ] || die "sinfo lists no node in $where (is SLURM reachable? is PARTITION right?)"
if [ -n "${CPUS:-}" ]; then
  [[ "$CPUS" =~ ^[1-9][0-9]*$ ]] || die "CPUS must be a positive whole number, not '$CPUS'"
  [ "$CPUS" -le "$node_cpus" ] || die "CPUS=$CPUS but the largest node in $where has $node_cpus CPUs: the tasks could never start; set CPUS=$node_cpus or less, or another PARTITION"
  cpus="$CPUS"
else
  cpus=$((node_cpus < 4 ? node_cpus : 4))
fi

# Refuse while an earlier submission for this folder is live (its tasks hold the shard folders).
live="$(live_jobs "$out")"
[ -z "$live" ] || die "jobs of an earlier submission into $out are still queued or running ($(echo "$live" | paste -sd, -)); wait or scancel them first"
[ ! -e "$out/merged" ] || die "$out/merged already exists: remove it (or choose another OUT) to merge again"

mkdir -p "$out/logs" "$out/slurm/status"
rm -f "$out/slurm/status/"*
echo "$n" >"$out/slurm/shards"
# The job scripts: a header of settings (shell-quoted), then a fixed body.
header() {
  echo "#!/usr/bin/env bash"
  echo "# $1, written by scripts/slurm_array.sh for shards of $spec."
  echo "set -uo pipefail"
  printf 'cd %q\n' "$workdir"
  [ -z "$data" ] || printf 'export SOMNURBS_DATA=%q\n' "$data"
  printf 'bin=%q out=%q n=%q cpus=%q\n' "$bin" "$out" "$n" "$cpus"
  printf 'run_args=(%s)\n' "$( ((${#run_args[@]})) && printf '%q ' "${run_args[@]}")"
  printf 'spec=%q\n' "$spec"
}
{
  header "Task I of the array: shard I/N into OUT/shard_I"
  cat <<'BODY'
i=$SLURM_ARRAY_TASK_ID
status="$out/slurm/status/shard_$i"
echo "running (job $SLURM_JOB_ID on $(hostname -s) since $(date -u +%FT%TZ))" >"$status"
"$bin" run "$spec" "${run_args[@]}" --shard "$i/$n" --resume --jobs "$cpus" --out "$out/shard_$i"
rc=$?
echo "exit $rc" >"$status"
exit $rc
BODY
} >"$out/slurm/shard.sh"
{
  header "Merge job, run after every task of the array has ended"
  cat <<'BODY'
failed=()
shards=()
for i in $(seq 1 "$n"); do
  shards+=("$out/shard_$i")
  s=$(cat "$out/slurm/status/shard_$i" 2>/dev/null || echo 'never started')
  case "$s" in
    'exit 0') continue ;;
    exit*) why="failed ($s)" ;;
    running*) why="was killed while $s (time limit, cancelled or node failure)" ;;
    *) why='never started (cancelled?)' ;;
  esac
  failed+=("shard $i/$n $why, see $out/logs/shard_$i.log")
done
if [ ${#failed[@]} -gt 0 ]; then
  printf 'slurm_array: merge refused: %s\n' "${failed[@]}" >&2
  echo "failed: $(printf '%s; ' "${failed[@]}")re-submit the same command to resume" >"$out/slurm/status/merge"
  exit 1
fi
echo "running (job $SLURM_JOB_ID since $(date -u +%FT%TZ))" >"$out/slurm/status/merge"
"$bin" merge "${shards[@]}" --jobs "$cpus" --out "$out/merged"
rc=$?
echo "exit $rc" >"$out/slurm/status/merge"
exit $rc
BODY
} >"$out/slurm/merge.sh"
chmod +x "$out/slurm/shard.sh" "$out/slurm/merge.sh"

part_args=()
[ -n "$partition" ] && part_args=(--partition "$partition")
# shellcheck disable=SC2086  # SBATCH_ARGS is a list of options
array_id=$(sbatch --parsable ${SBATCH_ARGS:-} "${part_args[@]}" --job-name "somnurbs-$name" --array "1-$n" \
  --cpus-per-task "$cpus" --time "${TIME:-01:00:00}" --output "$out/logs/shard_%a.log" "$out/slurm/shard.sh")
array_id="${array_id%%;*}"
# shellcheck disable=SC2086
merge_id=$(sbatch --parsable ${SBATCH_ARGS:-} "${part_args[@]}" --job-name "somnurbs-$name-merge" \
  --dependency "afterany:$array_id" --kill-on-invalid-dep=yes \
  --cpus-per-task "$cpus" --time "${MERGE_TIME:-00:30:00}" --output "$out/logs/merge.log" "$out/slurm/merge.sh")
merge_id="${merge_id%%;*}"
printf 'array %s\nmerge %s\n' "$array_id" "$merge_id" >"$out/slurm/jobs"
echo "submitted array $array_id ($n shards of $spec, $cells cells, $cpus CPUs each) and merge $merge_id (after every shard)"
echo "progress: scripts/slurm_array.sh --status $out"
echo "results: $out/merged (logs in $out/logs)"
