#include "core/log.h"

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

namespace npt {

void init_logging(Verbosity verbosity) {
    // Plain (uncoloured) stderr sink: messages read like compiler diagnostics and stdout stays free for
    // results.
    spdlog::drop("nerfpt");  // so that a second call (tests) replaces the logger instead of throwing
    auto logger = spdlog::stderr_logger_mt("nerfpt");
    logger->set_pattern("nerfpt: %l: %v");
    switch (verbosity) {
        case Verbosity::Quiet:
            logger->set_level(spdlog::level::err);
            break;
        case Verbosity::Normal:
            logger->set_level(spdlog::level::info);
            break;
        case Verbosity::Verbose:
            logger->set_level(spdlog::level::debug);
            break;
    }
    spdlog::set_default_logger(logger);
}

}  // namespace npt
