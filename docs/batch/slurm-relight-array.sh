#!/bin/bash
# A catalogue relight job as a Slurm job array (issue #23): 50 shards of 10 000 frames
# (50 environments × 200 rotations), each task rendering its block of 200 frames into one
# folder on a shared file system. Slurm sets SLURM_ARRAY_TASK_ID (0-49 here);
# `--shard-count 50` reads it.
#
#   jid=$(sbatch --parsable slurm-relight-array.sh)
#   sbatch --dependency=afterok:$jid slurm-finalize.sh frames
#
#SBATCH --job-name=btf-relight
#SBATCH --array=0-49%25
#SBATCH --cpus-per-task=2
#SBATCH --mem=4G
#SBATCH --time=01:00:00
#SBATCH --requeue
#SBATCH --output=logs/%x-%A_%a.out
set -euo pipefail
export BTF_NO_PROGRESS=1
envs=()
for e in envs/*.exr; do envs+=(--env "$e"); done
srun btf relight scene.toml "${envs[@]}" --rotations 200 -o frames --shard-count 50
