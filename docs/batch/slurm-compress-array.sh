#!/bin/bash
# A material library's compression as a Slurm job array (issue #23): 8 shards of one
# store, each a task that computes its block of view slots into the shared OUT.eig.partial
# on a shared file system. Slurm sets SLURM_ARRAY_TASK_ID (0-7 here); `--shard-count 8`
# reads it. A failed task can be resubmitted alone (sbatch --array=3 …): it keeps the
# slots its earlier attempt finished.
#
#   jid=$(sbatch --parsable slurm-compress-array.sh library/wool.btf library/wool.eig)
#   sbatch --dependency=afterok:$jid slurm-finalize.sh library/wool.eig
#
#SBATCH --job-name=btf-compress
#SBATCH --array=0-7
#SBATCH --cpus-per-task=4
#SBATCH --mem=8G
#SBATCH --time=02:00:00
#SBATCH --requeue
#SBATCH --output=logs/%x-%A_%a.out
set -euo pipefail
in=${1:?usage: slurm-compress-array.sh IN.btf OUT.eig}
out=${2:?usage: slurm-compress-array.sh IN.btf OUT.eig}
export BTF_NO_PROGRESS=1
# Mixed nodes: pin the kernel path so every shard computes its slots the same way
# (the avx2 and avx512 paths give identical stores; scalar differs in the 12th digit).
export BTF_SIMD=${BTF_SIMD:-avx2}
export RAYON_NUM_THREADS=${SLURM_CPUS_PER_TASK:-4}
srun btf compress "$in" -c 16 -o "$out" --shard-count 8
