#!/usr/bin/env bash
# Shots on farms, end to end with the nerfpt binary and the checked-in animated scene (scenes/shot):
#  - examples/farm/slurm_shot.sh, run as a 3-task job array (SLURM's variables set here), writes every frame once,
#    each task only its chunk, and each frame is bitwise the frame a single process renders (per-frame seeds);
#  - a rerun skips what is written; a deleted and a truncated frame are rendered again, and only those;
#  - examples/farm/nerfpt-render.js, compiled by node with a stand-in for Flamenco's `author`, runs its commands;
#  - a shot killed (SIGKILL) or interrupted (SIGINT) mid-way leaves only whole frames, and the rerun finishes it.
# Usage: tests/cli/farm_test.sh path/to/nerfpt   (ctest passes the built binary)
set -euo pipefail

nerfpt=$(realpath "${1:?usage: farm_test.sh path/to/nerfpt}")
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
scene="$root/scenes/shot/scene.gltf"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
args=(--backend cpu --threads 1 --spp 4 --res 32x24)

# The reference: one process, frames 1-6.
mkdir -p "$tmp/one"
"$nerfpt" render "$scene" -o "$tmp/one/shot.####.exr" --frames 1-6 "${args[@]}" -q >"$tmp/one.log" 2>&1 ||
    fail "single-process render: $(cat "$tmp/one.log")"

same_frames() {  # same_frames DIR FRAME...: DIR's frames are byte for byte the reference's
    local dir=$1 f
    shift
    for f in "$@"; do
        cmp -s "$tmp/one/shot.$f.exr" "$dir/shot.$f.exr" || fail "$dir/shot.$f.exr differs from the single-process frame"
    done
}

# SLURM job array, 3 tasks over 6 frames: the script's own command, with the variables sbatch would set.
slurm() {  # slurm TASK_ID: runs the script as that array task; its output in $tmp/slurm.TASK.log
    env SLURM_ARRAY_TASK_ID="$1" SLURM_ARRAY_TASK_COUNT=3 SLURM_ARRAY_TASK_MIN=0 SLURM_CPUS_PER_TASK=1 \
        NERFPT="$nerfpt" SCENE="$scene" OUT="$tmp/slurm/shot.####.exr" FRAMES=1-6 \
        RENDER_ARGS="--backend cpu --spp 4 --res 32x24" \
        bash "$root/examples/farm/slurm_shot.sh" >"$tmp/slurm.$1.log" 2>&1 || fail "slurm task $1: $(cat "$tmp/slurm.$1.log")"
}
for task in 0 1 2; do
    slurm $task
    written=$(grep -c '^wrote .*shot\.[0-9]*\.exr' "$tmp/slurm.$task.log" || true)
    [[ $written -eq 2 ]] || fail "slurm task $task wrote $written frames, expected 2: $(cat "$tmp/slurm.$task.log")"
done
grep -q 'wrote .*shot.0003.exr' "$tmp/slurm.1.log" && grep -q 'wrote .*shot.0004.exr' "$tmp/slurm.1.log" ||
    fail "task 1 of 3 did not render frames 3 and 4"
[[ $(ls "$tmp/slurm"/shot.*.exr | wc -l) -eq 6 ]] || fail "the array did not write 6 frames: $(ls "$tmp/slurm")"
same_frames "$tmp/slurm" 0001 0002 0003 0004 0005 0006

# Resume: nothing left; then a deleted and a truncated frame are rendered again, and only those.
slurm 1
grep -q 'nothing to render' "$tmp/slurm.1.log" || fail "rerun of a finished task rendered: $(cat "$tmp/slurm.1.log")"
rm "$tmp/slurm/shot.0003.exr"
head -c 500 "$tmp/one/shot.0004.exr" >"$tmp/slurm/shot.0004.exr"
slurm 1
grep -q '2 of 2 frames to render' "$tmp/slurm.1.log" || fail "resume did not render exactly 2 frames: $(cat "$tmp/slurm.1.log")"
same_frames "$tmp/slurm" 0003 0004

# Flamenco: the job type compiled by node, with `author` and `job` standing in for the Manager's; each task's
# command run as a Worker would.
if command -v node >/dev/null; then
    mkdir -p "$tmp/flamenco"
    node - "$root/examples/farm/nerfpt-render.js" "$nerfpt" "$scene" "$tmp/flamenco/shot.####.exr" >"$tmp/flamenco.log" 2>&1 <<'JS' || fail "flamenco job type: $(cat "$tmp/flamenco.log")"
const fs = require("fs");
const { execFileSync } = require("child_process");
const [file, nerfpt, scene, output] = process.argv.slice(2);
const tasks = [];
const author = {
    Task: (name, type) => { const t = { name, type, commands: [] }; t.addCommand = (c) => t.commands.push(c); return t; },
    Command: (type, params) => ({ type, params }),
};
const compileJob = new Function("author", fs.readFileSync(file, "utf8") + "\nreturn compileJob;")(author);
compileJob({ settings: { nerfpt, scene, output, frame_first: 1, frame_last: 6, chunk_size: 4,
                         extra_args: "--backend cpu --threads 1 --spp 4 --res 32x24" },
             addTask: (t) => tasks.push(t) });
if (tasks.length !== 2) throw new Error(`expected 2 tasks, got ${tasks.length}`);
for (const t of tasks)
    for (const c of t.commands) {
        if (c.type !== "exec") throw new Error(`unexpected command type ${c.type}`);
        console.log(execFileSync(c.params.exe, c.params.args, { encoding: "utf8" }));
    }
JS
    same_frames "$tmp/flamenco" 0001 0002 0003 0004 0005 0006
else
    echo "node not found: the Flamenco job type's commands were not run"
fi

# Killed mid-shot: only whole frames, and the rerun renders exactly the rest. Slow frames (about a second each on
# one thread) so that the signal lands between the first frame and the last.
slow=(--backend cpu --threads 1 --spp 2000 --res 32x24)
for signal in KILL INT; do
    dir="$tmp/kill_$signal"
    mkdir -p "$dir"
    "$nerfpt" render "$scene" -o "$dir/shot.####.exr" --frames 1-6 "${slow[@]}" >"$dir.log" 2>&1 &
    pid=$!
    for _ in $(seq 1 600); do [[ -e "$dir/shot.0001.exr" ]] && break; sleep 0.05; done
    kill -s $signal $pid || fail "SIG$signal: the render had already ended: $(cat "$dir.log")"
    wait $pid 2>/dev/null || true
    n=$(ls "$dir"/shot.*.exr 2>/dev/null | wc -l)
    [[ $n -ge 1 && $n -lt 6 ]] || fail "SIG$signal: $n frames written before the signal (expected 1..5: the test needs a slower render)"
    "$nerfpt" render "$scene" -o "$dir/shot.####.exr" --frames 1-6 "${slow[@]}" -q >"$dir.rerun.log" 2>&1 ||
        fail "SIG$signal rerun: $(cat "$dir.rerun.log")"
    grep -q "^rendered $((6 - n)) frames in" "$dir.rerun.log" ||
        fail "SIG$signal rerun did not pick up where it stopped: $(cat "$dir.rerun.log")"
    ls "$dir" | grep -q tmp && fail "SIG$signal: temporary files left after the rerun: $(ls "$dir")"
done

if [[ $failures -gt 0 ]]; then
    echo "$failures failure(s)"
    exit 1
fi
echo "all farm tests passed"
