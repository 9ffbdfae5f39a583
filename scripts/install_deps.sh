#!/usr/bin/env bash
# Installs the Debian 12 packages nerfpt needs to build and test. Checks with dpkg first, so a re-run installs
# nothing and does not touch the network; runs `apt-get update` only when something is missing. Works as a
# normal user when everything is installed; otherwise it names the packages to install (or use sudo).
set -euo pipefail

packages=(
    cmake ninja-build g++ pkg-config git
    libembree-dev libtbb-dev
    libtinygltf-dev libtinyobjloader-dev libopenexr-dev libstb-dev nlohmann-json3-dev
    zlib1g-dev  # compressed instant-ngp snapshots (.ingp)
    libcli11-dev libspdlog-dev libfmt-dev
    libgtest-dev libgmock-dev libbenchmark-dev
    libeigen3-dev
    libopenvdb-dev libnanovdb-dev libboost-dev  # OpenVDB 10 headers include Boost; Debian does not depend on it
    python3
    ffmpeg colmap  # nerfpt curate / poses / capture drive these command-line tools (and their end-to-end test)
    blender python3-numpy  # the Blender add-on (blender/nerfpt_blender) and its tests (ctest -L blender)
    libopenmpi-dev openmpi-bin  # mpirun -np N nerfpt render (NERFPT_MPI) and its tests (tests/cli/mpi_test.sh)
    clang libclang-rt-14-dev  # the ASan + UBSan build and the libFuzzer harnesses (scripts/test.sh, scripts/fuzz.sh)
    libturbojpeg0-dev nodejs chromium  # nerfpt serve: JPEG frames; node + npm fetch the page's assets; its browser test
)
# Debian's nodejs comes without npm; NodeSource's nodejs has it and conflicts with Debian's npm package.
command -v npm >/dev/null 2>&1 || packages+=(npm)

missing=()
for p in "${packages[@]}"; do
    # "install ok installed" is the only state in which the package's files are all there.
    if [[ "$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)" != "install ok installed" ]]; then
        missing+=("$p")
    fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
    echo "install_deps: all ${#packages[@]} packages are installed"
    exit 0
fi

echo "install_deps: missing: ${missing[*]}"
if [[ $(id -u) -ne 0 ]]; then
    if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
        sudo_cmd=(sudo)
    else
        echo "install_deps: not root; install them with:" >&2
        echo "  sudo apt-get update && sudo apt-get install -y --no-install-recommends ${missing[*]}" >&2
        exit 1
    fi
else
    sudo_cmd=()
fi

export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "install_deps: installed ${#missing[@]} packages"
