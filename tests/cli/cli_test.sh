#!/usr/bin/env bash
# Command-line behaviour of the nerfpt binary: help texts, exit codes and one-line error messages.
# Usage: tests/cli/cli_test.sh path/to/nerfpt   (ctest passes the built binary)
set -euo pipefail

nerfpt=${1:?usage: cli_test.sh path/to/nerfpt}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
scene="$here/../../scenes/example/scene.gltf"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0

fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# run ARGS...: runs nerfpt, leaving the exit code in $rc and the outputs in $tmp/out, $tmp/err.
run() {
    rc=0
    "$nerfpt" "$@" >"$tmp/out" 2>"$tmp/err" || rc=$?
}

# expect_error CODE PATTERN ARGS...: exit code CODE, exactly one line on stderr, matching PATTERN (grep -E).
expect_error() {
    local code=$1 pattern=$2
    shift 2
    run "$@"
    local what="nerfpt $*"
    [[ $rc -eq $code ]] || fail "$what: exit code $rc, expected $code"
    [[ $(wc -l <"$tmp/err") -eq 1 ]] || fail "$what: expected one line on stderr, got: $(cat "$tmp/err")"
    grep -qE "^nerfpt: error: " "$tmp/err" || fail "$what: stderr does not start with 'nerfpt: error: '"
    grep -qE -- "$pattern" "$tmp/err" || fail "$what: stderr does not match '$pattern': $(cat "$tmp/err")"
}

# --help mentions every option of each command.
run --help
[[ $rc -eq 0 ]] || fail "--help: exit code $rc"
for opt in --version --verbose --quiet render info train eval view bake import-ngp pose-error; do
    grep -q -- "$opt" "$tmp/out" || fail "nerfpt --help does not mention $opt"
done
run render --help
[[ $rc -eq 0 ]] || fail "render --help: exit code $rc"
for opt in SCENE --output --spp --res --max-depth --seed --threads --backend --camera --exposure --transparent --aov \
    --aov-files; do
    grep -q -- "$opt" "$tmp/out" || fail "nerfpt render --help does not mention $opt"
done
run info --help
[[ $rc -eq 0 ]] || fail "info --help: exit code $rc"
for opt in SCENE --camera; do
    grep -q -- "$opt" "$tmp/out" || fail "nerfpt info --help does not mention $opt"
done
run eval --help
[[ $rc -eq 0 ]] || fail "eval --help: exit code $rc"
for opt in MODEL DATA --split --output --every --downscale --threads --alpha --masks PSNR SSIM metrics.json; do
    grep -q -- "$opt" "$tmp/out" || fail "nerfpt eval --help does not mention $opt"
done
run view --help
[[ $rc -eq 0 ]] || fail "view --help: exit code $rc"
for opt in MODEL --output --camera --split --orbit --res --fov --elevation --distance --fps --object --threads ffmpeg "+Z"; do
    grep -q -- "$opt" "$tmp/out" || fail "nerfpt view --help does not mention $opt"
done
run bake --help
[[ $rc -eq 0 ]] || fail "bake --help: exit code $rc"
for opt in MODEL --output --res --voxel --crop --format --direction --threshold --threads "view-dependent"; do
    grep -q -- "$opt" "$tmp/out" || fail "nerfpt bake --help does not mention $opt"
done
expect_error 1 "MODEL.*does-not-exist.npt" bake "$tmp/does-not-exist.npt" -o "$tmp/x.vdb"
expect_error 2 "--res" bake "$tmp/does-not-exist.npt" -o "$tmp/x.vdb" --res 0
expect_error 1 "model.*does-not-exist.npt" isolate "$tmp/does-not-exist.npt" -o "$tmp/x.npt"
expect_error 2 "--min-component" isolate "$tmp/does-not-exist.npt" -o "$tmp/x.npt" --min-component 0
expect_error 2 "--plane-margin" isolate "$tmp/does-not-exist.npt" -o "$tmp/x.npt" --plane-margin -1
run --version
if [[ $rc -ne 0 ]] || ! grep -qE '^nerfpt [0-9]+\.[0-9]+' "$tmp/out"; then
    fail "--version: exit code $rc, '$(cat "$tmp/out")'"
fi

# Usage errors: exit code 2.
expect_error 2 "subcommand"
expect_error 2 "--output" render "$scene"
expect_error 2 "--res" render "$scene" -o "$tmp/a.exr" --res 0x0
expect_error 2 "--res" render "$scene" -o "$tmp/a.exr" --res abc
expect_error 2 "--res" render "$scene" -o "$tmp/a.exr" --res 100000x10
expect_error 2 "--res" render "$scene" -o "$tmp/a.exr" --res -5x10
expect_error 2 "--res" render "$scene" -o "$tmp/a.exr" --res 64x
# --aov: names the bad value; --aov-files needs --aov; the output folder must exist with AOVs too.
expect_error 2 "--aov: 'albedo,nrm': 'nrm' is not an AOV" render "$scene" -o "$tmp/a.exr" --aov albedo,nrm
expect_error 2 "--aov: '': an empty name" render "$scene" -o "$tmp/a.exr" --aov ""
expect_error 2 "--aov-files requires --aov" render "$scene" -o "$tmp/a.exr" --aov-files
expect_error 1 "folder '.*/no_such_dir' does not exist" render "$scene" -o "$tmp/no_such_dir/a.exr" --aov depth --aov-files
expect_error 2 "--spp" render "$scene" -o "$tmp/a.exr" --spp 0
expect_error 2 "--max-depth" render "$scene" -o "$tmp/a.exr" --max-depth -3
expect_error 2 "--writers" render "$scene" -o "$tmp/a.####.exr" --frames 1-2 --writers 0
expect_error 1 "--writers: is for sequences" render "$scene" -o "$tmp/a.exr" --writers 2
expect_error 2 "unknown backend 'vulkan'" render "$scene" -o "$tmp/a.exr" --backend vulkan

# Errors a user can act on: exit code 1, one line naming the thing.
expect_error 1 "missing\.gltf" render "$tmp/missing.gltf" -o "$tmp/a.exr"
expect_error 1 "missing\.gltf" info "$tmp/missing.gltf"
expect_error 2 "unknown backend 'gpu'" render "$scene" -o "$tmp/a.exr" --backend gpu
expect_error 1 "--denoise: the denoiser is OptiX's" render "$scene" -o "$tmp/a.exr" --denoise
expect_error 1 "--denoise: the denoiser is OptiX's; it does not run with --backend cpu" render "$scene" -o "$tmp/a.exr" --denoise --backend cpu
# Without a usable OptiX backend (CI: not built, or no GPU) asking for it is an error, never a silent fallback.
if [[ -z "${NERFPT_CLI_HAS_GPU:-}" ]]; then
    expect_error 1 "--backend optix: " render "$scene" -o "$tmp/a.exr" --backend optix
fi
expect_error 1 "no_such_folder.*does not exist" render "$scene" -o "$tmp/no_such_folder/a.exr"
expect_error 1 "\.exr" render "$scene" -o "$tmp/a.png"
expect_error 1 "camera 'nope'" info "$scene" --camera nope

# The output checks come before the scene is loaded: a missing scene and a bad output report the output.
expect_error 1 "no_such_folder" render "$tmp/missing.gltf" -o "$tmp/no_such_folder/a.exr"

# eval and view check their paths before loading anything, so these need no real model: a file that is not
# a model stands in where the check must stop earlier.
printf 'not a model' >"$tmp/bad.npt"
expect_error 2 "--every" eval "$tmp/bad.npt" "$tmp" --every 0
expect_error 2 "--downscale" eval "$tmp/bad.npt" "$tmp" --downscale 0
expect_error 2 "--alpha requires --output" eval "$tmp/bad.npt" "$tmp" --alpha
expect_error 2 "excludes" view "$tmp/bad.npt" -o "$tmp/a.png" --camera "$tmp:0" --orbit 10
expect_error 2 "--elevation" view "$tmp/bad.npt" -o "$tmp/a.mp4" --elevation 90
expect_error 2 "--res" view "$tmp/bad.npt" -o "$tmp/a.mp4" --res 0x10
expect_error 1 "MODEL.*missing\.npt.*not found" eval "$tmp/missing.npt" "$tmp"
expect_error 1 "MODEL.*is a folder" eval "$tmp" "$tmp"
expect_error 1 "DATA.*no_data" eval "$tmp/bad.npt" "$tmp/no_data"
expect_error 1 "--masks.*no_masks.*no such file" eval "$tmp/bad.npt" "$tmp" --masks "$tmp/no_masks"
expect_error 1 "--masks.*bad\.npt.*not a folder" eval "$tmp/bad.npt" "$tmp" --masks "$tmp/bad.npt"
expect_error 1 "--output.*not a folder" eval "$tmp/bad.npt" "$tmp" -o "$tmp/bad.npt"
expect_error 1 "bad\.npt" eval "$tmp/bad.npt" "$tmp"
expect_error 1 "MODEL.*missing\.npt" view "$tmp/missing.npt" -o "$tmp/a.mp4"
expect_error 1 "\.mp4 or \.png" view "$tmp/bad.npt" -o "$tmp/a.gif"
expect_error 1 "no_such_folder.*does not exist" view "$tmp/bad.npt" -o "$tmp/no_such_folder/a.mp4"
expect_error 1 "DATA:INDEX" view "$tmp/bad.npt" -o "$tmp/a.png" --camera nothing
expect_error 1 "no_data" view "$tmp/bad.npt" -o "$tmp/a.png" --camera "$tmp/no_data:3"
expect_error 1 "one image.*\.png" view "$tmp/bad.npt" -o "$tmp/a.mp4" --camera "$tmp:0"
expect_error 1 "even width and height" view "$tmp/bad.npt" -o "$tmp/a.mp4" --res 101x100
expect_error 1 "bad\.npt" view "$tmp/bad.npt" -o "$tmp/a.png"
expect_error 2 "--output.*required" import-ngp "$tmp/bad.npt"
expect_error 1 "missing\.ingp: no such file" import-ngp "$tmp/missing.ingp" -o "$tmp/imported.npt"
expect_error 1 "bad\.npt: not a MessagePack snapshot" import-ngp "$tmp/bad.npt" -o "$tmp/imported.npt"
[[ ! -e "$tmp/imported.npt" ]] || fail "import-ngp wrote a model from a bad snapshot"
# Without ffmpeg on PATH an .mp4 is refused before any work (nerfpt itself runs from its full path).
printf '#!/bin/sh\nPATH=/nonexistent exec "%s" "$@"\n' "$nerfpt" >"$tmp/nerfpt_no_ffmpeg"
chmod +x "$tmp/nerfpt_no_ffmpeg"
real_nerfpt=$nerfpt
nerfpt="$tmp/nerfpt_no_ffmpeg"
expect_error 1 "ffmpeg on PATH" view "$tmp/bad.npt" -o "$tmp/a.mp4"
nerfpt=$real_nerfpt

# A tiny render works and writes both files.
run -q render "$scene" -o "$tmp/small.exr" --res 16x12 --spp 1 --threads 1
[[ $rc -eq 0 ]] || fail "tiny render: exit code $rc: $(cat "$tmp/err")"
[[ -s "$tmp/small.exr" && -s "$tmp/small.png" ]] || fail "tiny render: small.exr / small.png not written"
grep -q "16x12" "$tmp/out" || fail "tiny render: summary does not name the resolution: $(cat "$tmp/out")"
[[ ! -s "$tmp/err" ]] || fail "tiny render with -q wrote to stderr: $(cat "$tmp/err")"
# The same with a transparent film and every AOV, the AOVs also as files beside it.
run -q render "$scene" -o "$tmp/film.exr" --res 16x12 --spp 1 --threads 1 --backend cpu --transparent \
    --aov albedo,normal,depth --aov-files
[[ $rc -eq 0 ]] || fail "render --transparent --aov: exit code $rc: $(cat "$tmp/err")"
for f in film.exr film.png film.albedo.exr film.normal.exr film.depth.exr; do
    [[ -s "$tmp/$f" ]] || fail "render --transparent --aov --aov-files: $f not written"
    grep -q "$f" "$tmp/out" || fail "render --aov-files: the summary does not name $f"
done

# info describes the example scene.
run info "$scene"
[[ $rc -eq 0 ]] || fail "info: exit code $rc: $(cat "$tmp/err")"
for word in meshes materials lights spot camera volumes nerf_volume render; do
    grep -q "$word" "$tmp/out" || fail "info does not mention '$word'"
done

# poses: bad folders, too few frames, COLMAP missing (PATH without it), a bad matcher.
expect_error 1 "not a folder of frames" poses "$tmp/no_such_frames" -o "$tmp/transforms.json"
mkdir -p "$tmp/frames"
cp "$here/../../docs/images/cornell_256spp.png" "$tmp/frames/a.png"
expect_error 1 "1 images .* at least 3" poses "$tmp/frames" -o "$tmp/transforms.json"
cp "$tmp/frames/a.png" "$tmp/frames/b.png"
cp "$tmp/frames/a.png" "$tmp/frames/c.png"
cp "$tmp/frames/a.png" "$tmp/frames/contact_sheet.png"  # curate's sheet: not a frame
mkdir -p "$tmp/emptybin"
rc=0
PATH="$tmp/emptybin" "$nerfpt" poses "$tmp/frames" -o "$tmp/transforms.json" >"$tmp/out" 2>"$tmp/err" || rc=$?
[[ $rc -eq 1 ]] || fail "poses without colmap: exit code $rc"
grep -q "'colmap' not found on PATH: install COLMAP" "$tmp/err" || fail "poses without colmap: $(cat "$tmp/err")"
[[ ! -e "$tmp/transforms.json" ]] || fail "poses without colmap wrote transforms.json"
expect_error 2 "matcher" poses "$tmp/frames" -o "$tmp/transforms.json" --matcher fancy
# --poses-quality: documented, and anything but fast/balanced/best refused before COLMAP runs.
run poses --help
[[ $rc -eq 0 ]] || fail "poses --help: exit code $rc"
for opt in --poses-quality fast balanced best --threads --matcher --min-registered --camera-model OPENCV RADIAL \
    SIMPLE_RADIAL PINHOLE SIMPLE_PINHOLE; do
    grep -q -- "$opt" "$tmp/out" || fail "nerfpt poses --help does not mention $opt"
done
expect_error 2 "--poses-quality.*fastest" poses "$tmp/frames" -o "$tmp/transforms.json" --poses-quality fastest
expect_error 2 "--poses-quality" poses "$tmp/frames" -o "$tmp/transforms.json" --poses-quality
expect_error 2 "--threads" poses "$tmp/frames" -o "$tmp/transforms.json" --threads -1
# --camera-model: COLMAP's models that transforms.json can hold, by COLMAP's names; others refused up front.
expect_error 2 "--camera-model.*FISHEYE" poses "$tmp/frames" -o "$tmp/transforms.json" --camera-model FISHEYE

# capture: missing video, missing tools, a work folder that holds another video's capture, bad options.
run capture --help
for opt in --target-frames --matcher --poses-quality --camera-model --holdout-every --train-time --train-steps --downscale \
    --turntable-frames --keep-scene --force; do
    grep -q -- "$opt" "$tmp/out" || fail "nerfpt capture --help does not mention $opt"
done
expect_error 1 "VIDEO.*no_such.mp4" capture "$tmp/no_such.mp4" -o "$tmp/cap"
touch "$tmp/clip.mp4" "$tmp/other.mp4"
rc=0
PATH="$tmp/emptybin" "$nerfpt" capture "$tmp/clip.mp4" -o "$tmp/cap" >"$tmp/out" 2>"$tmp/err" || rc=$?
[[ $rc -eq 1 ]] || fail "capture without tools: exit code $rc"
grep -q "ffmpeg, ffprobe, colmap not found on PATH.*apt-get install ffmpeg colmap" "$tmp/err" ||
    fail "capture without tools: $(cat "$tmp/err")"
[[ ! -e "$tmp/cap" ]] || fail "capture without tools created its work folder"
expect_error 2 "holdout-every" capture "$tmp/clip.mp4" -o "$tmp/cap" --holdout-every -1
expect_error 2 "downscale" capture "$tmp/clip.mp4" -o "$tmp/cap" --downscale 100
expect_error 2 "--poses-quality.*exhaustive" capture "$tmp/clip.mp4" -o "$tmp/cap" --poses-quality exhaustive
if command -v ffmpeg >/dev/null && command -v colmap >/dev/null; then
    expect_error 1 "holdout-every 1" capture "$tmp/clip.mp4" -o "$tmp/cap" --holdout-every 1
    ffmpeg -nostdin -v error -f lavfi -i testsrc=size=64x48:rate=10 -frames:v 10 -pix_fmt yuv420p "$tmp/real.mp4"
    mkdir -p "$tmp/cap"
    echo "{\"version\": 1, \"video\": \"$tmp/other.mp4\", \"stages\": {}}" >"$tmp/cap/capture.json"
    expect_error 1 "capture.json: this folder holds the capture of .*other.mp4.*--force" \
        capture "$tmp/real.mp4" -o "$tmp/cap"
    echo "{" >"$tmp/cap/capture.json"
    expect_error 1 "capture.json: not valid JSON.*--force" capture "$tmp/real.mp4" -o "$tmp/cap"
    # An empty file is not a video: refused before the work folder is made.
    expect_error 1 "clip.mp4: not a video" capture "$tmp/clip.mp4" -o "$tmp/cap2"
    [[ ! -e "$tmp/cap2" ]] || fail "capture of a non-video created its work folder"
fi
run pose-error --help
[[ $rc -eq 0 ]] || fail "pose-error --help: exit code $rc"
for opt in ESTIMATE REFERENCE --match --known-rate --json --pieces Umeyama; do
    grep -q -- "$opt" "$tmp/out" || fail "nerfpt pose-error --help does not mention $opt"
done
# pose-error: bad inputs, then four cameras against a moved and scaled copy of themselves (zero error).
expect_error 2 "--match" pose-error "$tmp/a.json" "$tmp/b.json" --match fancy
expect_error 1 "ESTIMATE '.*missing\.json': no such file" pose-error "$tmp/missing.json" "$tmp/b.json"
expect_error 1 "neither a COLMAP model" pose-error "$tmp/frames" "$tmp/frames"
expect_error 1 "--known-rate needs --match rate" pose-error "$tmp/frames" "$tmp/frames" --known-rate 10 0
poses_json() {  # poses_json SCALE OFFSET: cameras at SCALE * corner + OFFSET, identity rotations
    local s=$1 o=$2 frames="" i=0 c
    for c in "0 0 0" "1 0 0" "0 1 0" "0 0 1"; do
        set -- $c
        frames+="${frames:+,}{\"file_path\": \"images/frame_0000$i.png\", \"transform_matrix\": [[1,0,0,$(($1 * s + o))],[0,1,0,$(($2 * s + o))],[0,0,1,$(($3 * s + o))],[0,0,0,1]]}"
        i=$((i + 1))
    done
    echo "{\"frames\": [$frames]}"
}
poses_json 1 0 >"$tmp/a.json"
poses_json 3 5 >"$tmp/b.json"
printf '{"frames": [{"file_path": "x.png"}]}' >"$tmp/bad.json"
expect_error 1 "bad\.json: frame 0 \('x\.png'\): missing 'transform_matrix'" pose-error "$tmp/bad.json" "$tmp/b.json"
run pose-error "$tmp/a.json" "$tmp/b.json" --json "$tmp/pose_error.json"
[[ $rc -eq 0 ]] || fail "pose-error: exit code $rc: $(cat "$tmp/err")"
grep -qE "matched cameras +4" "$tmp/out" || fail "pose-error: table does not say 4 matched: $(cat "$tmp/out")"
grep -qE "alignment scale +3 " "$tmp/out" || fail "pose-error: alignment scale is not 3: $(cat "$tmp/out")"
grep -q '"matched": 4' "$tmp/pose_error.json" || fail "pose-error --json: no '\"matched\": 4'"
expect_error 1 "--known-rate: A must be a positive" pose-error "$tmp/a.json" "$tmp/b.json" --match rate --known-rate 0 1
run pose-error "$tmp/a.json" "$tmp/b.json" --match rate --known-rate 1 0
grep -qE "video frame 1\.0000 i \+ 0\.00" "$tmp/out" || fail "pose-error --known-rate: $(cat "$tmp/out" "$tmp/err")"
grep -qE "matched cameras +4" "$tmp/out" || fail "pose-error --known-rate: not 4 matched: $(cat "$tmp/out")"
# --pieces: a reference whose path leaps once (between frames 3 and 4), and an estimate whose second piece sits
# elsewhere: the global fit is off, each piece on its own fits exactly.
pieces_json() {  # pieces_json X Y: the second piece moved by (X, Y, 0)
    local dx=$1 dy=$2 frames="" i=0 c
    for c in "0 0 0" "1 0 0" "1 1 0" "1 1 1" "100 0 0" "101 0 0" "101 1 0" "101 1 1"; do
        set -- $c
        if [[ $i -ge 4 ]]; then set -- $(($1 + dx)) $(($2 + dy)) $3; fi
        frames+="${frames:+,}{\"file_path\": \"frame_0000$i.png\", \"transform_matrix\": [[1,0,0,$1],[0,1,0,$2],[0,0,1,$3],[0,0,0,1]]}"
        i=$((i + 1))
    done
    echo "{\"frames\": [$frames]}"
}
pieces_json 0 0 >"$tmp/ref_pieces.json"
pieces_json -90 40 >"$tmp/est_pieces.json"
run pose-error "$tmp/est_pieces.json" "$tmp/ref_pieces.json" --pieces --json "$tmp/pieces.json"
[[ $rc -eq 0 ]] || fail "pose-error --pieces: exit code $rc: $(cat "$tmp/err")"
grep -qE "^frame_00000\.png\.\.frame_00003\.png +4 +0\.000 +0\.000 +0\.000 +0\.000 +1 *$" "$tmp/out" ||
    fail "pose-error --pieces: no exact row for the first piece: $(cat "$tmp/out")"
grep -qE "^frame_00004\.png\.\.frame_00007\.png +4 +0\.000 +0\.000 +0\.000 +0\.000 +1 *$" "$tmp/out" ||
    fail "pose-error --pieces: no exact row for the second piece: $(cat "$tmp/out")"
grep -q '"pieces"' "$tmp/pieces.json" || fail "pose-error --pieces --json: no 'pieces'"

# Reliability (issue 15). A scene without a camera renders from the default view (it aborted inside Embree).
printf 'v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n' >"$tmp/tri.obj"
run -q render "$tmp/tri.obj" -o "$tmp/tri.exr" --res 8x8 --spp 1 --threads 1
[[ $rc -eq 0 && -s "$tmp/tri.exr" ]] || fail "render of an OBJ without a camera: exit code $rc: $(cat "$tmp/err")"
# Numbers are strict for every option: NaN and infinity, a negative unsigned, octal-looking integers.
expect_error 2 "--exposure.*'nan' is not a finite number" render "$scene" -o "$tmp/a.exr" --exposure nan
expect_error 2 "--seed.*'-1' is not a whole number >= 0" render "$scene" -o "$tmp/a.exr" --seed -1
expect_error 2 "--spp.*'010'" render "$scene" -o "$tmp/a.exr" --spp 010
expect_error 2 "--time.*'nan'" train "$tmp" -o "$tmp/nan.npt" --time nan
expect_error 2 "--surface-smoothness.*-1" train "$tmp" -o "$tmp/nan.npt" --surface-smoothness -1
expect_error 2 "--relight-average.*1" train "$tmp" -o "$tmp/nan.npt" --relightable --relight-average 1
expect_error 2 "--relight-seed.*'-3'" train "$tmp" -o "$tmp/nan.npt" --relightable --relight-seed -3
# A resumed model keeps its config: the loss weight cannot change under it.
printf 'x' >"$tmp/kept.npt"
expect_error 1 "--surface-smoothness: a resumed model keeps the config" train "$tmp" -o "$tmp/kept.npt" --resume \
    --surface-smoothness 0.1
expect_error 2 "--fov.*'nan'" view "$tmp/bad.npt" -o "$tmp/a.png" --fov nan
expect_error 2 "--distance.*inf" view "$tmp/bad.npt" -o "$tmp/a.png" --distance inf
[[ ! -e "$tmp/nan.npt" ]] || fail "train --time nan wrote a model"
# compare names both files when their sizes differ.
run -q render "$scene" -o "$tmp/other.exr" --res 8x6 --spp 1 --threads 1
expect_error 1 "small\.exr' is 16x12 but REFERENCE .*other\.exr' is 8x6" compare "$tmp/small.exr" "$tmp/other.exr"
# No command writes over its own input, --force or not: a render whose PNG preview is the scene's texture.
printf 'mtllib tex.mtl\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\nvt 0 0\nusemtl t\nf 1/1 2/1 3/1\n' >"$tmp/tex.obj"
printf 'newmtl t\nmap_Kd tex.png\n' >"$tmp/tex.mtl"
cp "$here/../../docs/images/cornell_256spp.png" "$tmp/tex.png"
expect_error 1 "--output '.*tex\.png': is the input texture" render "$tmp/tex.obj" -o "$tmp/tex.exr"
cmp -s "$tmp/tex.png" "$here/../../docs/images/cornell_256spp.png" || fail "render replaced its own texture"
[[ ! -e "$tmp/tex.exr" ]] || fail "render wrote tex.exr although tex.png is its input"
mkdir -p "$tmp/ngp"
printf 'x' >"$tmp/ngp/snap.msgpack"
expect_error 1 "is the input SNAPSHOT" import-ngp "$tmp/ngp/snap.msgpack" -o "$tmp/ngp/./snap.msgpack"

if [[ $failures -gt 0 ]]; then
    echo "$failures check(s) failed"
    exit 1
fi
echo "all CLI checks passed"
