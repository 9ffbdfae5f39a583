#!/usr/bin/env bash
# Installs what is missing, builds Release in build/ and runs every test that needs no GPU and is not labelled
# `long`. Extra arguments go to ctest (e.g. scripts/test.sh -R Progress -V). Exits non-zero when the build or a
# test fails.
#
# --sanitize (first argument): instead, the ASan + UBSan build in build-san/ (clang; scripts/configure_sanitize.sh):
# the unit and CLI tests under the sanitizers, then every fuzz harness for $NERFPT_FUZZ_SECONDS (default 10)
# seconds each (scripts/fuzz.sh, as many at once as build jobs). Any sanitizer report fails the run.
# --sanitize --quick (what CI runs) skips the CLI build and the tests that train, render or check numerics for
# long (numerics, not input handling; under ASan they took 5 of its 11 minutes on one core): the slow list below,
# each with what still runs its code under the sanitizers.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
jobs=${NERFPT_JOBS:-$(nproc)}

if [[ "${1:-}" == "--sanitize" ]]; then
    shift
    quick=0
    if [[ "${1:-}" == "--quick" ]]; then
        quick=1
        shift
    fi
    start=$(date +%s)
    scripts/configure_sanitize.sh
    # Leaks are reported too; a UB report stops the test that made it (-fno-sanitize-recover). A failed
    # allocation is a std::bad_alloc, as in a normal build (cmake/sanitizer_new.cpp).
    export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:allocator_may_return_null=1}
    export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
    export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/cmake/lsan_suppressions.txt}
    if [[ $quick -eq 1 ]]; then
        cmake --build build-san -j "$jobs" --target nerfpt_unit_tests fuzzers
        # NerfTraining, BakeRoundTrip, TrainResume, EvalViewCli, FitTimeMapping: minutes of training and rendering.
        # MlpBatch.GradientsMatchFiniteDifferencesColourNetwork (20 s under ASan): the library's forward and
        # backward run once, the time goes to the test's double-precision finite differences; the same shape's
        # backward runs in MlpBatch.BackwardAdds..., the density network's finite differences still run.
        # WavefrontSegment.AQueued... (7 s): 300 rays marched twice to compare numbers; OtherSegments... runs the
        # same hand-over code. RelightSamples.EventDraws... (~100 s: 300 steps of training before a small
        # gather): RelightSamples.BorrowingPixels... trains the same model and runs the same gather code.
        slow='NerfTraining\.|BakeRoundTrip\.|TrainResume\.|EvalViewCli\.|FitTimeMapping'
        slow+='|MlpBatch\.GradientsMatchFiniteDifferencesColourNetwork|WavefrontSegment\.AQueuedNerfSegment'
        slow+='|RelightSamples\.EventDrawsLieOnThePointsCameraRay'
        # BakeColour (240 s under ASan: a trained model baked 9 times, 36 renders): Bake.* bake and write the
        # same grids, the VDB reader tests (vdb_grid_reader_test.cpp) read such files back.
        # RelightTrainer.PrefilteredSpecular... (215 s: 3000 fit steps and a fine quadrature in the test):
        # PrefilteredGradientMatchesFiniteDifferences... runs the same estimator, forward and backward.
        slow+='|BakeColour\.|RelightTrainer\.PrefilteredSpecularRecoversAGlossyAlbedo'
        # RelightTrainer.RecoversAKnownAlbedo... (46 s: 1500 fit steps): GradientMatchesFiniteDifferences... runs
        # the sampled estimator's forward and backward. PathIntegrator.WhiteFurnaceGgxConductor (55 s): the
        # integrator runs in WhiteFurnaceLambert, the conductor BSDF in Conductor.WhiteFurnace... .
        slow+='|RelightTrainer\.RecoversAKnownAlbedo|PathIntegrator\.WhiteFurnaceGgxConductor'
        (cd build-san && ctest -L unit -E "$slow" --output-on-failure -j "$jobs" "$@")
    else
        cmake --build build-san -j "$jobs" --target nerfpt_unit_tests nerfpt_cli fuzzers
        (cd build-san && ctest -L "unit|cli" --output-on-failure -j "$jobs" "$@")
    fi
    NERFPT_FUZZ_JOBS=${NERFPT_FUZZ_JOBS:-$jobs} scripts/fuzz.sh "${NERFPT_FUZZ_SECONDS:-10}"
    echo "test.sh --sanitize: $(($(date +%s) - start)) s"
    exit 0
fi

scripts/configure.sh
# Default: all cores; CI machines have 2, shared machines can set NERFPT_JOBS.
cmake --build build -j "$jobs"

cd build
# `long`: end-to-end tests of many CPU minutes (tests/e2e_long), run by hand (ctest -L long), not in CI's 40.
ctest -LE 'gpu|long' --output-on-failure -j "$jobs" "$@"
