// What every subcommand shares: the global options (set once in main) and the interrupt guard.
#pragma once

#include "core/log.h"

namespace npt::cli {

class InterruptGuard;

// Global options, parsed before any subcommand runs and passed down (no global state).
struct GlobalSettings {
    bool verbose = false;
    bool quiet = false;
    Verbosity verbosity() const {
        return quiet ? Verbosity::Quiet : (verbose ? Verbosity::Verbose : Verbosity::Normal);
    }
};

// The version printed by --version; the build may pass the project version in.
#ifdef NERFPT_VERSION
constexpr const char* k_version = NERFPT_VERSION;
#else
constexpr const char* k_version = "0.1.0";
#endif

}  // namespace npt::cli
