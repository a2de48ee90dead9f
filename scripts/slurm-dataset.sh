#!/bin/bash
# Renders a geltip dataset on a Slurm cluster: a job array with one task per shard, then
# one merge job that starts once every task has succeeded (--dependency=afterok).
#
#   scripts/slurm-dataset.sh --sensor paper --count 1000000 --seed 1 --shards 16 \
#       --out $SCRATCH/geltip/train \
#       [--shard-dir DIR] [--tasks 3,7] [--geltip PATH] \
#       [--sbatch ARG]... [--merge-sbatch ARG]... [-- DATASET OPTIONS...]
#
#   --shards N        shards (array tasks); shard i renders into <shard-dir>/<i>
#   --shard-dir DIR   where the shards go (default <out>.shards); Slurm's logs go to DIR/logs
#   --tasks LIST      submit only these shards (e.g. 3,7 or 0-3): after a task was preempted
#                     or ran out of time, the same command with --tasks resumes it, and
#                     submits the merge again
#   --geltip PATH     the geltip binary the jobs run (default: geltip on PATH)
#   --sbatch ARG      an sbatch option for every shard task, e.g. --sbatch --gres=gpu:1
#                     --sbatch --time=02:00:00 --sbatch --cpus-per-task=4 (repeatable)
#   --merge-sbatch ARG  an sbatch option for the merge job (repeatable)
#   -- ...            options every shard's `geltip dataset` gets: --masks, --noise 2, ...
#
# Prints one JSON line: the array's and the merge's job ids and the directories.
set -euo pipefail

die() {
    echo "slurm-dataset.sh: $*" >&2
    exit 2
}

sensor="" count="" seed="" shards="" out="" shard_dir="" tasks="" geltip=""
array_opts=() merge_opts=() dataset_opts=()
while [ $# -gt 0 ]; do
    case "$1" in
    --sensor | --count | --seed | --shards | --out | --shard-dir | --tasks | --geltip | \
        --sbatch | --merge-sbatch)
        [ $# -ge 2 ] || die "$1 needs a value"
        case "$1" in
        --sensor) sensor=$2 ;;
        --count) count=$2 ;;
        --seed) seed=$2 ;;
        --shards) shards=$2 ;;
        --out) out=$2 ;;
        --shard-dir) shard_dir=$2 ;;
        --tasks) tasks=$2 ;;
        --geltip) geltip=$2 ;;
        --sbatch) array_opts+=("$2") ;;
        --merge-sbatch) merge_opts+=("$2") ;;
        esac
        shift 2
        ;;
    --)
        shift
        dataset_opts=("$@")
        break
        ;;
    -h | --help)
        sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
        exit 0
        ;;
    *) die "unknown option $1 (--help lists them)" ;;
    esac
done

[ -n "$sensor" ] || die "--sensor is required"
[ -n "$out" ] || die "--out is required"
[[ "$count" =~ ^[0-9]+$ ]] && [ "$count" -ge 1 ] || die "--count must be a whole number >= 1, got '$count'"
[[ "${seed:=0}" =~ ^[0-9]+$ ]] || die "--seed must be a whole number, got '$seed'"
[[ "$shards" =~ ^[0-9]+$ ]] && [ "$shards" -ge 1 ] || die "--shards must be a whole number >= 1, got '$shards'"
[ -n "$tasks" ] || tasks="0-$((shards - 1))"
[[ "$tasks" =~ ^[0-9,-]+$ ]] || die "--tasks must list shard indices like 3,7 or 0-3, got '$tasks'"
command -v sbatch >/dev/null || die "sbatch not found: run this on a Slurm login node"
geltip=$(command -v "${geltip:-geltip}") || die "geltip not found: give --geltip <path to the binary>"
geltip=$(realpath "$geltip")
out=$(realpath -m "$out")
shard_dir=$(realpath -m "${shard_dir:-$out.shards}")
mkdir -p "$shard_dir/logs"

# The shard count is written into the task's command: SLURM_ARRAY_TASK_COUNT would be the
# number of tasks submitted, which --tasks makes smaller than the shard count.
shard_cmd=$(printf '%q ' "$geltip" dataset --sensor "$sensor" --count "$count" --seed "$seed" \
    "${dataset_opts[@]}")
shard_dir_q=$(printf '%q' "$shard_dir")
array_job=$(sbatch --parsable --job-name=geltip-dataset --array="$tasks" \
    --output="$shard_dir/logs/shard-%a.%A.out" "${array_opts[@]}" <<EOF
#!/bin/bash
set -euo pipefail
exec $shard_cmd --shard "\$SLURM_ARRAY_TASK_ID/$shards" --out $shard_dir_q/"\$SLURM_ARRAY_TASK_ID"
EOF
)
array_job=${array_job%%;*}

shard_dirs=()
for ((i = 0; i < shards; i++)); do shard_dirs+=("$shard_dir/$i"); done
merge_cmd=$(printf '%q ' "$geltip" dataset --merge "$out" "${shard_dirs[@]}")
merge_job=$(sbatch --parsable --job-name=geltip-merge --dependency="afterok:$array_job" \
    --kill-on-invalid-dep=yes --output="$shard_dir/logs/merge.%j.out" "${merge_opts[@]}" <<EOF
#!/bin/bash
set -euo pipefail
exec $merge_cmd
EOF
)
merge_job=${merge_job%%;*}

printf '{"array_job": "%s", "merge_job": "%s", "shards": "%s", "out": "%s"}\n' \
    "$array_job" "$merge_job" "$shard_dir" "$out"
