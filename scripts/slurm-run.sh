#!/usr/bin/env bash
# Run a Monte-Carlo scenario on a Slurm cluster: a job array of N shards
# (`axiscal run SCENARIO --shard K/N`), then a merge job that starts when every shard
# succeeded (`axiscal merge`), giving the same results as one `axiscal run SCENARIO`.
#
# Usage: scripts/slurm-run.sh SCENARIO N [sbatch options...]
#   e.g. scripts/slurm-run.sh scenarios/perturbed-fleet.toml 16 --partition=short --time=00:30:00
#
# Environment:
#   AXISCAL  the binary (default target/release/axiscal; build it first with
#            `cargo build --release`, on a file system every node sees)
#   OUT      results folder (default results/<scenario file stem>); shards go to
#            $OUT/shard-K-of-N, the merged results to $OUT/merged
#   CPUS     cores per shard (default 1; passed as --cpus-per-task and --threads)
#   DRY_RUN  set to 1 to print the sbatch commands instead of submitting them
#
# Every trial's seed is derived from the scenario seed and its index, so the merged results
# do not depend on N, on the cores per shard, or on the order the shards run in. The merge
# job exits 1 (and Slurm marks it FAILED) when a threshold of the scenario fails.
set -euo pipefail

if [[ $# -lt 2 ]]; then
    sed -n '2,12p' "$0" >&2
    exit 2
fi
scenario=$1
shards=$2
shift 2
if ! [[ $shards =~ ^[1-9][0-9]*$ ]]; then
    echo "N must be a positive integer, got '$shards'" >&2
    exit 2
fi
if [[ ! -f $scenario ]]; then
    echo "no scenario file $scenario" >&2
    exit 2
fi
bin=${AXISCAL:-target/release/axiscal}
name=$(basename "$scenario" .toml)
out=${OUT:-results/$name}
cpus=${CPUS:-1}

shard_cmd="$bin run $scenario --shard \${SLURM_ARRAY_TASK_ID}/$shards --threads $cpus --force --out $out/shard-\${SLURM_ARRAY_TASK_ID}-of-$shards"
merge_cmd="$bin merge $out/shard-*-of-$shards --force --out $out/merged"

submit() {
    if [[ ${DRY_RUN:-0} == 1 ]]; then
        printf 'sbatch' >&2
        printf ' %q' "$@" >&2
        printf '\n' >&2
        echo "DRYRUN_$RANDOM"
    else
        sbatch --parsable "$@"
    fi
}

mkdir -p "$out"
array_id=$(submit --array="1-$shards" --cpus-per-task="$cpus" --job-name="axiscal-$name" \
    --output="$out/slurm-%A_%a.out" "$@" --wrap "$shard_cmd")
array_id=${array_id%%;*}
merge_id=$(submit --dependency="afterok:$array_id" --job-name="axiscal-$name-merge" \
    --output="$out/slurm-merge-%j.out" "$@" --wrap "$merge_cmd")
merge_id=${merge_id%%;*}
echo "submitted shards as job array $array_id and the merge as job $merge_id; results in $out/merged"
