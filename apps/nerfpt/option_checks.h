// Strict numbers on the command line, for every option of every subcommand at once. CLI11 converts with
// strtod/strtoull: "nan" and "inf" pass its Range checks (every comparison with NaN is false), "-1" becomes
// 2^64 - 1 in an unsigned option, and "010" is octal 8 in an integer one.
#pragma once

#include <CLI/CLI.hpp>

namespace npt::cli {

// Adds to every option of `app` and its subcommands, by the option's value type: FLOAT must be a finite
// number, INT an optional '-' and decimal digits, UINT decimal digits only. Call after all options are
// added, before parsing; the usual Range checks still apply after these.
void check_numbers_strictly(CLI::App& app);

}  // namespace npt::cli
