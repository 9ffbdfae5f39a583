#!/usr/bin/env bash
# A SLURM job array that renders a shot with nerfpt, one chunk of frames per array task:
#   sbatch --array=0-7 examples/farm/slurm_shot.sh
# nerfpt reads SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT (and SLURM_ARRAY_TASK_MIN, for --array=1-8) and
# renders the task's contiguous chunk of FRAMES. Frames already written are skipped, so resubmitting the array
# after a failure renders only what is missing. Settings through the environment (sbatch --export=ALL,...):
#   SCENE   the scene (default scenes/shot/scene.gltf)     OUT    the frames, #### = frame (default renders/shot.####.exr)
#   FRAMES  FIRST-LAST[:STEP] (default 1-48)                NERFPT the binary (default: nerfpt on PATH)
#   RENDER_ARGS  more `nerfpt render` options, e.g. "--spp 256 --res 1920x1080"
#SBATCH --job-name=nerfpt-shot
#SBATCH --cpus-per-task=16
#SBATCH --output=nerfpt-shot-%A_%a.log
set -euo pipefail
SCENE=${SCENE:-scenes/shot/scene.gltf}
OUT=${OUT:-renders/shot.####.exr}
FRAMES=${FRAMES:-1-48}
NERFPT=${NERFPT:-nerfpt}
mkdir -p "$(dirname "$OUT")"
# shellcheck disable=SC2086  # RENDER_ARGS is a list of options
exec "$NERFPT" render "$SCENE" -o "$OUT" --frames "$FRAMES" --threads "${SLURM_CPUS_PER_TASK:-0}" ${RENDER_ARGS:-}
