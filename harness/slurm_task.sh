#!/bin/sh
# The script of Penumbra's Slurm jobs (sbatch needs a script, not a binary):
# it runs its arguments as they are, `penumbra run-batch BATCH` for an array
# task or `penumbra run STUDY ...` for the report job. Nothing from a study
# becomes shell code here: paths arrive as arguments, never as text.
exec "$@"
