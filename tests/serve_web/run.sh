#!/usr/bin/env bash
# nerfpt serve in a real browser (ctest serve.browser): Debian's chromium, headless, driven by puppeteer-core
# (never a browser puppeteer downloads). Usage: run.sh NERFPT_BINARY WORK_DIR [SCREENSHOT_DIR]
# Exits 77 (ctest: skipped) with one line saying why when chromium, node/npm or the npm package is missing.
set -euo pipefail
nerfpt=$1
work=$(realpath -m "$2")
shots=$(realpath -m "${3:-$work/screenshots}")
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
chromium=${NERFPT_CHROMIUM:-/usr/bin/chromium}
skip() { echo "SKIPPED: serve.browser: $*"; exit 77; }
[[ -x "$chromium" ]] || skip "no $chromium (scripts/install_deps.sh installs chromium)"
command -v node >/dev/null || skip "no node (scripts/install_deps.sh installs nodejs)"
command -v npm >/dev/null || skip "no npm"
mkdir -p "$work" "$shots"
deps="$work/node_modules/puppeteer-core/package.json"
if [[ ! -f "$deps" || "$here/package-lock.json" -nt "$deps" ]]; then
    cp "$here/package.json" "$here/package-lock.json" "$work/"
    (cd "$work" && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund --ignore-scripts --loglevel=error) \
        || skip "npm ci of puppeteer-core failed (no registry?)"
fi
scene_dir="$work/scene"
rm -rf "$scene_dir" && mkdir -p "$scene_dir"
cp "$here/../data/serve/"* "$scene_dir/"
cp "$here/viewer_test.mjs" "$here/train_test.mjs" "$here/report_test.mjs" "$work/"
cd "$work"
NERFPT="$nerfpt" SCENE="$scene_dir/scene.json" SHOTS="$shots" CHROMIUM="$chromium" node viewer_test.mjs
# nerf train --serve's page: needs NeRF-synthetic lego (../shared/data); without it, that part is skipped.
lego=${NERFPT_LEGO:-$here/../../../shared/data/nerf_synthetic/lego}
if [[ -f "$lego/transforms_train.json" ]]; then
    NERFPT="$nerfpt" LEGO="$(realpath "$lego")" WORK="$work" SHOTS="$shots" CHROMIUM="$chromium" node train_test.mjs
    # nerfpt serve CAPTURE_DIR's report, on a capture folder made from that training's model.
    NERFPT="$nerfpt" LEGO="$(realpath "$lego")" WORK="$work" SHOTS="$shots" CHROMIUM="$chromium" node report_test.mjs
else
    echo "serve.browser: no $lego: the training page's and the capture report's tests are skipped"
fi
