#!/usr/bin/env bash
# GPU cycle for the lent GPU machine (no Debian libraries there, no package registry, 64 MiB may travel):
#   scripts/gpu_check.sh pack       here: build the GPU binaries for sm_90 (the nerfpt CLI, the GPU tests and
#                                   the benchmarks; the OptiX backend when .optix/ holds the SDK headers) and
#                                   pack them with the non-system shared libraries they need into
#                                   .gpu/bundle.tar.xz, plus the lego views the benchmarks use (100 training
#                                   views, every 4th test view), the Cornell reference scenes and the NeRF
#                                   demo scenes into .gpu/
#   scripts/gpu_check.sh bundle BIN...  here: only the named binaries (nerfpt, relight_fields, render_bench,
#                                   nerfpt_gpu_tests, ...), stripped, with their libraries, into .gpu/bundle.tar.xz
#                                   (a smaller carry when .gpu/relight must travel too); builds nothing
#   scripts/gpu_check.sh run        there (carry .gpu): unpack and run every GPU-labelled test
#   scripts/gpu_check.sh bench ...  there, after run: bench/train_bench with the given arguments
# The unpacked binaries are in /tmp/nerfpt-gpu/bin; NERFPT_CLI points the tests at the CLI there.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-}
unpacked=/tmp/nerfpt-gpu

unpack() {
    # Again when the bundle changed: a warm machine keeps the last call's binaries, which may be another bundle's.
    local sum
    sum=$(cksum <.gpu/bundle.tar.xz)
    if [[ ! -x $unpacked/bin/nerfpt || $(cat $unpacked/.bundle_sum 2>/dev/null) != "$sum" ]]; then
        rm -rf $unpacked
        mkdir -p $unpacked
        tar -xJf .gpu/bundle.tar.xz -C $unpacked
        echo "$sum" >$unpacked/.bundle_sum
    fi
    export LD_LIBRARY_PATH="$unpacked/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    export NERFPT_CLI=$unpacked/bin/nerfpt
    export NERFPT_SHARED_DATA="$PWD/.gpu"  # the benchmarks find nerf_synthetic/lego there
}

stage_libs() {  # every library ldd resolves outside the C runtime (the GPU machine runs another distribution)
    for b in .gpu/stage/bin/*; do ldd "$b"; done | awk '/=> \// {print $3}' | sort -u |
        grep -v -E '/(libc|libm|libdl|libpthread|librt|libgcc_s|libstdc\+\+|ld-linux[^/]*|libcuda)\.so' |
        xargs -r -I{} cp -L {} .gpu/stage/lib/
}
write_bundle() {  # .gpu/stage/bin with its libraries -> .gpu/bundle.tar.xz
    stage_libs
    # xz -9e: ~15% smaller than tar -J, which is what lets the tests and the data fit in one 64 MiB carry
    tar -cf - -C .gpu/stage bin lib | xz -9e -T0 >.gpu/bundle.tar.xz
    rm -rf .gpu/stage
}
case "$mode" in
bundle)
    build=${BUILD_DIR:-build}
    rm -rf .gpu/stage && mkdir -p .gpu/stage/bin .gpu/stage/lib
    for name in "${@:2}"; do
        file=$(find "$build" -maxdepth 3 -type f -name "$name" -perm -u+x | head -1)
        [[ -n $file ]] || { echo "gpu_check: no binary '$name' under $build (build it first)" >&2; exit 1; }
        strip -o ".gpu/stage/bin/$name" "$file"
    done
    write_bundle
    du -h .gpu/bundle.tar.xz
    ;;
pack)
    build=${BUILD_DIR:-build}
    cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DNERFPT_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
        ${CUDACXX:+-DCMAKE_CUDA_COMPILER=$CUDACXX} >/dev/null
    cmake --build "$build" --target nerfpt_gpu_tests nerfpt_cli train_bench view_bench render_bench relight_fields
    rm -rf .gpu/stage && mkdir -p .gpu/stage/bin .gpu/stage/lib
    cp "$build/tests/nerfpt_gpu_tests" "$build/nerfpt" "$build/bench/train_bench" "$build/bench/view_bench" \
        "$build/bench/render_bench" "$build/bench/relight_fields" .gpu/stage/bin/
    write_bundle
    # The lego views the benchmarks read: the training set and test views 0, 4, 8, ... (train_bench
    # --test-every 4 on the full set scores the same 50 views as --test-every 1 on this one).
    # The reference scenes the OptiX parity tests and render_bench use (a few MB).
    scenes=${NERFPT_SHARED_DATA:-../shared/data}/scenes
    if [[ -d $scenes ]]; then
        rm -rf .gpu/scenes && mkdir -p .gpu/scenes
        cp -r "$scenes/cornell" "$scenes/cornell_volume" .gpu/scenes/
    fi
    # The model-in-scene demo (the NeRF queried directly, and its 256^3 bake), for the OptiX parity test and
    # render_bench; the GPU run trains the lego.npt these name.
    rm -rf .gpu/nerf_demo && mkdir -p .gpu/nerf_demo
    python3 scripts/make_nerf_demo_scene.py .gpu/nerf_demo/scene.gltf >/dev/null
    python3 scripts/make_nerf_demo_scene.py .gpu/nerf_demo/scene_baked.gltf lego_256.vdb >/dev/null
    python3 scripts/make_nerf_demo_shot.py .gpu/nerf_demo/scene.gltf .gpu/nerf_demo/shot.gltf  # bench/shot_gpu.sh
    src=${NERFPT_SHARED_DATA:-../shared/data}/nerf_synthetic/lego
    if [[ -d $src ]]; then
        dst=.gpu/nerf_synthetic/lego
        rm -rf "$dst" && mkdir -p "$dst/test"
        cp -r "$src/train" "$src/transforms_train.json" "$dst/"
        python3 - "$src" "$dst" <<'EOF'
import json, shutil, sys
src, dst = sys.argv[1], sys.argv[2]
t = json.load(open(f"{src}/transforms_test.json"))
t["frames"] = t["frames"][::4]
for f in t["frames"]:
    shutil.copy(f"{src}/{f['file_path']}.png", f"{dst}/{f['file_path']}.png")
json.dump(t, open(f"{dst}/transforms_test.json", "w"), indent=1)
EOF
    fi
    # The relighting set (issue 24) for scripts/gpu_relight_cycle.sh: carry .gpu/relight when it is needed.
    rsrc=${NERFPT_SHARED_DATA:-../shared/data}/relight
    if [[ -d $rsrc/dev ]]; then
        rm -rf .gpu/relight && mkdir -p .gpu/relight
        cp -r "$rsrc/dev" "$rsrc/score.py" .gpu/relight/
    fi
    du -sh .gpu
    ;;
run)
    unpack
    nvidia-smi -L
    nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.mem,memory.total --format=csv
    status=0
    # Line-buffered: a test that hangs until the caller's timeout still leaves what ran before it in the log.
    stdbuf -oL $unpacked/bin/nerfpt_gpu_tests --gtest_brief=1 "${@:2}" || status=$?
    echo "gpu_check: nerfpt_gpu_tests exit code $status"
    exit $status
    ;;
bench)
    unpack
    $unpacked/bin/train_bench "${@:2}"
    ;;
*)
    echo "usage: scripts/gpu_check.sh pack|bundle BIN...|run [gtest options]|bench [train_bench options]" >&2
    exit 2
    ;;
esac
