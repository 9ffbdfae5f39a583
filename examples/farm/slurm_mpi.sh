#!/usr/bin/env bash
# One SLURM job of N MPI ranks that renders a shot (frames split over the ranks) or, without FRAMES, a still
# (its samples split over the ranks; the EXR is bitwise the one-process render on the CPU backend):
#   sbatch --nodes=4 --ntasks-per-node=1 --cpus-per-task=32 examples/farm/slurm_mpi.sh
# nerfpt must be built with MPI (NERFPT_MPI, Open MPI). Rank 0 lists the frames still missing, so resubmitting
# after a failure renders only those, spread over every rank. Settings through the environment:
#   SCENE   the scene (default scenes/shot/scene.gltf)   OUT    the output (default renders/shot.####.exr)
#   FRAMES  FIRST-LAST[:STEP] (default 1-48; empty: a still, OUT without ####)   NERFPT the binary (default nerfpt)
#   RENDER_ARGS  more `nerfpt render` options, e.g. "--spp 256 --res 1920x1080"
#   NP      ranks when not under SLURM (default 2)    MPIRUN_ARGS  more mpirun options (e.g. --oversubscribe)
#SBATCH --job-name=nerfpt-mpi
#SBATCH --output=nerfpt-mpi-%j.log
set -euo pipefail
SCENE=${SCENE:-scenes/shot/scene.gltf}
OUT=${OUT:-renders/shot.####.exr}
FRAMES=${FRAMES-1-48}
NERFPT=${NERFPT:-nerfpt}
mkdir -p "$(dirname "$OUT")"
frames=()
[[ -n $FRAMES ]] && frames=(--frames "$FRAMES")
# shellcheck disable=SC2086  # MPIRUN_ARGS and RENDER_ARGS are lists of options
exec mpirun -np "${SLURM_NTASKS:-${NP:-2}}" ${MPIRUN_ARGS:-} "$NERFPT" render "$SCENE" -o "$OUT" "${frames[@]}" \
    --threads "${SLURM_CPUS_PER_TASK:-0}" ${RENDER_ARGS:-}
