// Logging setup for front ends: one spdlog logger on stderr whose level follows --verbose / --quiet. The
// library logs through spdlog's default logger; only main() calls init_logging, once, before any work.
#pragma once

namespace npt {

enum class Verbosity { Quiet, Normal, Verbose };

// Installs a stderr logger with a short "nerfpt: warning: ..." style prefix and sets its level:
// Quiet shows errors only, Normal shows info and up, Verbose shows debug and up.
void init_logging(Verbosity verbosity);

}  // namespace npt
