#!/usr/bin/env bash
# MPI on the CPU (issue 26): 2 ranks x 1 thread against 1 process x 1 thread, the frames of a shot split and the
# samples of a still split, each timed as a whole command (wall seconds, the median of 5 runs after a warm-up; the
# MPI start-up, about 0.3 s, included). Needs a quiet machine with 2 cores.
# Usage: [STILL_SPP=640] bench/mpi_cpu.sh [BUILD_DIR]   (the scene: scenes/shot, the checked-in animated one; a
# higher STILL_SPP makes the still's fixed MPI start-up a smaller share of its time)
set -euo pipefail
cd "$(dirname "$0")/.."
nerfpt=$(realpath "${1:-build}/nerfpt")
scene=scenes/shot/scene.gltf
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
frames=(render "$scene" --backend cpu --threads 1 --spp 32 --res 160x120 --frames 1-24 --overwrite -q
    -o "$tmp/shot.####.exr")
still=(render "$scene" --backend cpu --threads 1 --spp "${STILL_SPP:-640}" --res 160x120 -q -o "$tmp/still.exr")
one() { "$nerfpt" "$@" >/dev/null; }
two() { mpirun -np 2 --bind-to core "$nerfpt" "$@" >/dev/null; }
median() {  # median CMD...: 5 runs after a warm-up, wall seconds
    "$@"
    for _ in 1 2 3 4 5; do
        s=$(date +%s.%N)
        "$@"
        echo "$(date +%s.%N) - $s" | bc
    done | sort -n | sed -n 3p
}
for case in frames still; do
    declare -n args=$case
    t1=$(median one "${args[@]}")
    t2=$(median two "${args[@]}")
    printf '%-7s 1 process x 1 thread %6.2f s   2 ranks x 1 thread %6.2f s   speed-up %.2fx\n' "$case" "$t1" "$t2" \
        "$(echo "$t1 / $t2" | bc -l)"
done
