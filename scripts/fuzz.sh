#!/usr/bin/env bash
# Fuzzes every loader with libFuzzer (clang, ASan + UBSan) for SECONDS each (default 60), one after the other
# (NERFPT_FUZZ_JOBS at once), or until NERFPT_FUZZ_RUNS executions when that comes first.
# Usage: scripts/fuzz.sh [SECONDS] [TARGET...]   e.g. scripts/fuzz.sh 600 gltf obj
# Targets: gltf obj json_scene transforms config model_file volume_grid ngp_snapshot colmap image serve_message.
#
# Builds fuzz/ in build-san/ (scripts/configure_sanitize.sh), seeds each corpus from our own test data (the
# files the unit tests write under build-san/test_tmp, running the loader tests first when there are none, and
# the example scene), keeps each growing corpus in build-san/fuzz/corpus/TARGET, and stops at the first
# finding: libFuzzer prints the sanitizer report and saves the input as build-san/fuzz/crash-* (reproduce with
# build-san/fuzz/fuzz_TARGET FILE). Exits non-zero when any target found something. Prints each target's
# executions and exec/s. NERFPT_JOBS sets build jobs. The campaign in docs/benchmarks.md:
#   NERFPT_FUZZ_RUNS=1000000 NERFPT_FUZZ_JOBS=1 nice scripts/fuzz.sh 14400
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

seconds=${1:-60}
[[ $# -gt 0 ]] && shift
all=(gltf obj json_scene transforms config model_file volume_grid ngp_snapshot colmap image serve_message)
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=("${all[@]}")

build=${NERFPT_SAN_BUILD:-build-san}
if [[ ! -f "$build/build.ninja" ]]; then scripts/configure_sanitize.sh >/dev/null; fi
cmake --build "$build" -j "${NERFPT_JOBS:-$(nproc)}" --target fuzzers nerfpt_unit_tests

# A single allocation over 5 GiB fails with std::bad_alloc, as on a machine with that much memory
# (cmake/sanitizer_new.cpp): a loader must turn it into a one-line error. OpenVDB allocates whatever a size
# field in the file says before reading it, so a flipped bit there asks for 18 GB or 2^60 bytes.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1:max_allocation_size_mb=5120}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/cmake/lsan_suppressions.txt}

# Seeds: what the loader tests write (valid files and the bad ones they check), harvested by extension.
tmp_root="$build/test_tmp"
if [[ -z "$(ls -A "$tmp_root" 2>/dev/null)" ]]; then
    "$build/tests/nerfpt_unit_tests" --gtest_brief=1 \
        --gtest_filter='Gltf*:Obj*:JsonScene*:Dataset.*:NerfConfig*:ModelFile*:VdbGrid*:NanoVdb*:RawGrid*:NgpSnapshot*:Colmap*:ImageIo*' \
        >/dev/null 2>&1 || true
fi
seeds="$build/fuzz/seeds"
rm -rf "$seeds"
for t in "${all[@]}"; do mkdir -p "$seeds/$t" "$build/fuzz/corpus/$t"; done
n=0
seed() {  # seed TARGET FILE: copy FILE (at most 1 MiB) into the target's seeds
    local size
    size=$(stat -c %s "$2")
    [[ $size -le 1048576 ]] || return 0
    n=$((n + 1))
    cp "$2" "$seeds/$1/$n-$(basename "$2")"
}
while IFS= read -r -d '' f; do
    name=$(basename "$f")
    case "$name" in
        *.gltf | *.glb) seed gltf "$f" ;;
        *.obj)
            mtl=$(sed -n 's/^mtllib[ \t]*//p' "$f" | head -n 1 | tr -d '\r')
            if [[ -n "$mtl" && -f "$(dirname "$f")/$mtl" ]]; then
                n=$((n + 1))
                { sed 's/^mtllib .*/mtllib in.mtl/' "$f"; printf '\n#MTL\n'; cat "$(dirname "$f")/$mtl"; } >"$seeds/obj/$n-$name"
            else
                seed obj "$f"
            fi
            ;;
        transforms*.json) seed transforms "$f" ;;
        config*.json) seed config "$f" ;;
        *.json) seed json_scene "$f" ;;
        *.npt) seed model_file "$f" ;;
        *.msgpack | *.ingp) seed ngp_snapshot "$f" ;;
        # Grids over 256 KiB (the cornell volume's 1.8 MB) are left out: libFuzzer cut them at -max_len and
        # every mutation of one cost a multi-MB load: volume_grid ran at ~100 exec/s with them.
        *.vdb) [[ $(stat -c %s "$f") -le 262144 ]] && { n=$((n + 1)); { printf '\x00'; cat "$f"; } >"$seeds/volume_grid/$n.vdb"; } ;;
        *.nvdb) [[ $(stat -c %s "$f") -le 262144 ]] && { n=$((n + 1)); { printf '\x01'; cat "$f"; } >"$seeds/volume_grid/$n.nvdb"; } ;;
        [0-9]*x[0-9]*x[0-9]*_*.bin)
            IFS=x read -r w h d <<<"${name%%_*}"
            if [[ $w -le 255 && $h -le 255 && $d -le 255 && $w -ge 2 ]]; then
                n=$((n + 1))
                { printf "\\x$(printf %02x "$w")\\x$(printf %02x "$w")\\x$(printf %02x "$h")\\x$(printf %02x "$d")"
                  cat "$f"; } >"$seeds/volume_grid/$n.bin"
            fi
            ;;
        cameras.bin)
            dir=$(dirname "$f")
            if [[ -f "$dir/images.bin" && -f "$dir/points3D.bin" ]]; then
                n=$((n + 1))
                python3 - "$dir" "$seeds/colmap/$n.colmap" <<'PY'
import struct, sys, pathlib
d = pathlib.Path(sys.argv[1])
c, i, p = ((d / n).read_bytes() for n in ("cameras.bin", "images.bin", "points3D.bin"))
pathlib.Path(sys.argv[2]).write_bytes(struct.pack("<II", len(c), len(i)) + c + i + p)
PY
            fi
            ;;
        *.png | *.jpg | *.exr | *.hdr | *.bmp | *.tga) [[ $(stat -c %s "$f") -le 65536 ]] && seed image "$f" ;;
    esac
done < <(find "$tmp_root" scenes -type f -print0 2>/dev/null)
# nerfpt serve's messages: one of each type (tests/unit/serve_protocol_test.cpp has the bad ones).
for m in '{"type":"camera","position":[0,0,5],"forward":[0,0,-1],"up":[0,1,0],"fov_deg":40}' \
    '{"type":"volume","index":0,"translation":[1,0,0],"rotation":[0,0,0,1],"scale":[1,1,1],"density_scale":2,"crop":{"min":[0,0,0],"max":[1,1,1]},"shading":"relit"}' \
    '{"type":"settings","spp":8,"max_depth":4,"exposure":-1,"preview_divisor":2}' '{"type":"light","index":0,"intensity_scale":0.5}' \
    '{"type":"use_camera","index":0}' '{"type":"save"}' '{"type":"render","spp":4}' '{"type":"keyframes_save","seconds_per_key":1}'; do
    n=$((n + 1))
    printf '%s' "$m" >"$seeds/serve_message/$n.json"
done
# The raw-grid seeds above start with W (not 0 or 1): their first byte must differ from the OpenVDB/NanoVDB tags.
echo "fuzz: $n seed files from $tmp_root and scenes/"

# NERFPT_FUZZ_RUNS: also stop each target after this many executions (a campaign of N runs per loader);
# NERFPT_FUZZ_JOBS: targets fuzzed at once (default 1; each is one process on one core).
runs=${NERFPT_FUZZ_RUNS:-}
parallel=${NERFPT_FUZZ_JOBS:-1}
run_one() {  # run_one TARGET: exit status 0 when nothing was found
    local t=$1 limit=()
    [[ -z "$runs" ]] || limit=(-runs="$runs")
    # Memory: our largest documented allocation from a small file is a 2^28-voxel dense grid (4 GiB); more is a
    # finding.
    # Absolute paths: a harness makes its scratch folder the working directory at its first input, and
    # libFuzzer reads the seeds, writes new corpus entries and saves a crash after that.
    local dir
    dir=$(cd "$build/fuzz" && pwd)
    if ! (cd "$dir" && "./fuzz_$t" -max_total_time="$seconds" "${limit[@]}" -rss_limit_mb=6144 \
        -malloc_limit_mb=5120 -timeout=25 -max_len=1048576 -print_final_stats=1 -artifact_prefix="$dir/" \
        "$dir/corpus/$t" "$dir/seeds/$t" 2>"fuzz_$t.log"); then
        echo "fuzz: $t FOUND A PROBLEM: see $build/fuzz/fuzz_$t.log and $build/fuzz/crash-*" >&2
        tail -n 40 "$build/fuzz/fuzz_$t.log" >&2
        return 1
    fi
    echo "fuzz: $t: $(grep -E "stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)" \
        "$build/fuzz/fuzz_$t.log" | tr '\n' ' ')"
}
for t in "${targets[@]}"; do
    [[ -x "$build/fuzz/fuzz_$t" ]] || { echo "fuzz: unknown target '$t' (${all[*]})" >&2; exit 2; }
done
status=0
running=0
for t in "${targets[@]}"; do
    if [[ $running -ge $parallel ]]; then
        wait -n || status=1
        running=$((running - 1))
    fi
    echo "fuzz: $t for ${seconds}s${runs:+ or $runs runs}"
    run_one "$t" &
    running=$((running + 1))
done
while [[ $running -gt 0 ]]; do
    wait -n || status=1
    running=$((running - 1))
done
exit $status
