#!/usr/bin/env bash
# A fixed-N bias test split over a Slurm job array (docs/cluster.md): array task i of n renders
# shard i/n (the replicas of seeds ⌊i·N/n⌋..⌊(i+1)·N/n⌋; task 0 also the reference) into
# $SHARD_DIR/shard-i-of-n.json; `reshift merge $SHARD_DIR` then prints the test's outcome, bit
# for bit that of one run. Submit with task ids 0..n−1, from the folder the shards go under:
#   mkdir -p out/bias-shards && sbatch --wait --array=0-63 scripts/cluster/bias-array.sh
#SBATCH --job-name=reshift-bias
#SBATCH --cpus-per-task=2
#SBATCH --output=out/bias-shards/slurm-%A_%a.log
set -euo pipefail
# What to test: a ±1% verdict on restir:hybrid (δ = 0.01; N from a pilot run's "planned" line).
BIAS_ARGS=${BIAS_ARGS:---method restir:hybrid --replicas 4096 --delta 0.01}
SHARD_DIR=${SHARD_DIR:-out/bias-shards}
RESHIFT=${RESHIFT:-reshift}
# One shard per task: the array must be 0..n−1.
count=${SLURM_ARRAY_TASK_COUNT:?submit as a job array: sbatch --array=0-N}
index=${SLURM_ARRAY_TASK_ID:?submit as a job array: sbatch --array=0-N}
# shellcheck disable=SC2086 # BIAS_ARGS is a list of options
exec "$RESHIFT" bias $BIAS_ARGS --shard "$index/$count" --out "$SHARD_DIR"
