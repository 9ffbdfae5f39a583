#!/usr/bin/env bash
# nerfpt render under mpirun (registered when nerfpt is built with MPI), with the checked-in animated scene:
#  - a still's samples split over 2 and 3 ranks (an odd spp, alpha and AOVs) is byte for byte the one-process EXR;
#  - a shot's frames split over 2 ranks (examples/farm/slurm_mpi.sh's command) are byte for byte the one-process
#    frames;
#  - an error on every rank is one line, naming a rank;
#  - a rank killed (SIGKILL) mid-shot fails the job naming it, and the rerun renders only the missing frames
#    (spread over both ranks), every frame still the one-process frame.
# Usage: tests/cli/mpi_test.sh path/to/nerfpt path/to/mpiexec
set -euo pipefail

nerfpt=$(realpath "${1:?usage: mpi_test.sh path/to/nerfpt path/to/mpiexec}")
mpiexec=${2:?usage: mpi_test.sh path/to/nerfpt path/to/mpiexec}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
scene="$root/scenes/shot/scene.gltf"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
# CI runs as root; Open MPI refuses that unless told.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mpi() {  # mpi N ARGS...: nerfpt on N ranks of this machine (more ranks than cores allowed)
    local n=$1
    shift
    timeout 120 "$mpiexec" -np "$n" --oversubscribe "$nerfpt" "$@"
}

# A still, samples split: 13 spp do not divide evenly over 2 or 3 ranks.
still=(render "$scene" --backend cpu --threads 1 --spp 13 --res 40x30 --transparent --aov albedo,normal,depth -q)
"$nerfpt" "${still[@]}" -o "$tmp/still1.exr" >"$tmp/still1.log" 2>&1 || fail "one process: $(cat "$tmp/still1.log")"
for n in 2 3; do
    mpi $n "${still[@]}" -o "$tmp/still$n.exr" >"$tmp/still$n.log" 2>&1 || fail "$n ranks: $(cat "$tmp/still$n.log")"
    cmp -s "$tmp/still1.exr" "$tmp/still$n.exr" || fail "the still over $n ranks differs from one process's"
    cmp -s "$tmp/still1.png" "$tmp/still$n.png" || fail "the PNG over $n ranks differs from one process's"
done

# A shot, frames split.
shot=(render "$scene" --backend cpu --threads 1 --spp 4 --res 32x24 --frames 1-6)
mkdir -p "$tmp/one" "$tmp/two"
"$nerfpt" "${shot[@]}" -o "$tmp/one/shot.####.exr" -q >"$tmp/one.log" 2>&1 || fail "one process: $(cat "$tmp/one.log")"
# The 2 ranks through examples/farm/slurm_mpi.sh, as sbatch would run it (SLURM_NTASKS=2, one thread a rank).
env SLURM_NTASKS=2 SLURM_CPUS_PER_TASK=1 MPIRUN_ARGS=--oversubscribe NERFPT="$nerfpt" SCENE="$scene" \
    OUT="$tmp/two/shot.####.exr" FRAMES=1-6 RENDER_ARGS="--backend cpu --spp 4 --res 32x24" PATH="$(dirname "$mpiexec"):$PATH" \
    timeout 120 bash "$root/examples/farm/slurm_mpi.sh" >"$tmp/two.log" 2>&1 || fail "2 ranks: $(cat "$tmp/two.log")"
for f in 0001 0002 0003 0004 0005 0006; do
    cmp -s "$tmp/one/shot.$f.exr" "$tmp/two/shot.$f.exr" || fail "frame $f over 2 ranks differs from one process's"
done
grep -q 'rank 0 of 2: rendered 3 frames' "$tmp/two.log" && grep -q 'rank 1 of 2: rendered 3 frames' "$tmp/two.log" ||
    fail "the 6 frames were not split 3 and 3: $(cat "$tmp/two.log")"

# An error: one line, naming a rank.
if mpi 2 render "$tmp/missing.gltf" -o "$tmp/x.exr" >"$tmp/err.log" 2>&1; then fail "a missing scene succeeded"; fi
[[ $(grep -c '^nerfpt: error:' "$tmp/err.log") -eq 1 ]] && grep -q '^nerfpt: error: rank [01] of 2 on .*missing.gltf' "$tmp/err.log" ||
    fail "the error is not one line naming a rank: $(cat "$tmp/err.log")"

# A rank killed mid-shot, then the rerun. Slow frames (about a second each) so that the kill lands mid-way.
slow=(render "$scene" --backend cpu --threads 1 --spp 1000 --res 32x24 --frames 1-8 -o "$tmp/kill/shot.####.exr")
mkdir -p "$tmp/kill" "$tmp/ref"
mpi 2 "${slow[@]}" >"$tmp/kill.log" 2>&1 &
job=$!
for _ in $(seq 1 1200); do compgen -G "$tmp/kill/shot.*.exr" >/dev/null && break; sleep 0.05; done
killed=""
for pid in $(pgrep -f "$tmp/kill/shot" || true); do
    if tr '\0' '\n' <"/proc/$pid/environ" 2>/dev/null | grep -qx 'OMPI_COMM_WORLD_RANK=1'; then
        kill -KILL "$pid" && killed=$pid
    fi
done
[[ -n $killed ]] || fail "rank 1 was not found to kill: $(cat "$tmp/kill.log")"
if wait $job; then fail "the job with a killed rank succeeded: $(cat "$tmp/kill.log")"; fi
grep -q 'rank 1 .*signal 9' "$tmp/kill.log" || fail "the job's failure does not name rank 1: $(cat "$tmp/kill.log")"
n=$(ls "$tmp/kill"/shot.*.exr 2>/dev/null | wc -l)
[[ $n -ge 1 && $n -lt 8 ]] || fail "$n frames written before the kill (expected 1..7: the test needs a slower render)"
mpi 2 "${slow[@]}" >"$tmp/rerun.log" 2>&1 || fail "rerun: $(cat "$tmp/rerun.log")"
grep -q "$((8 - n)) of 8 frames to render ($n already done)" "$tmp/rerun.log" ||
    fail "the rerun did not render only the missing frames: $(cat "$tmp/rerun.log")"
rendered=$(grep -o 'rank [01] of 2: rendered [0-9]* frames' "$tmp/rerun.log" | awk '{s += $6} END {print s}')
[[ $rendered -eq $((8 - n)) ]] || fail "the rerun's ranks rendered $rendered frames, expected $((8 - n))"
"$nerfpt" "${slow[@]/$tmp\/kill/$tmp/ref}" -q >"$tmp/ref.log" 2>&1 || fail "reference: $(cat "$tmp/ref.log")"
for f in 0001 0002 0003 0004 0005 0006 0007 0008; do
    cmp -s "$tmp/ref/shot.$f.exr" "$tmp/kill/shot.$f.exr" || fail "frame $f after the kill and rerun differs from one process's"
done

if [[ $failures -gt 0 ]]; then
    echo "$failures failure(s)"
    exit 1
fi
echo "all MPI tests passed"
