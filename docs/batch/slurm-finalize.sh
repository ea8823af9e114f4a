#!/bin/bash
# The finalisation step of a sharded job (issue #23), run after the array:
#   sbatch --dependency=afterok:$jid slurm-finalize.sh OUT
# Idempotent: running it twice is harmless.
#SBATCH --job-name=btf-finalize
#SBATCH --cpus-per-task=1
#SBATCH --time=00:30:00
#SBATCH --output=logs/%x-%j.out
set -euo pipefail
out=${1:?usage: slurm-finalize.sh OUT}
btf status "$out"
btf finalize "$out"
