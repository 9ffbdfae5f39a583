// Counts the warnings spdlog's default logger emits while an instance is alive, so that tests can check that
// a loader warns exactly once per file. Restores the previous default logger on destruction.
#pragma once

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <memory>
#include <sstream>
#include <string>

namespace npt::test {

class LogCapture {
  public:
    LogCapture() : m_previous(spdlog::default_logger()) {
        auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(m_out);
        sink->set_pattern("%l|%v");
        auto logger = std::make_shared<spdlog::logger>("capture", sink);
        logger->set_level(spdlog::level::warn);
        spdlog::set_default_logger(logger);
    }
    ~LogCapture() { spdlog::set_default_logger(m_previous); }
    LogCapture(const LogCapture&) = delete;
    LogCapture& operator=(const LogCapture&) = delete;

    // Lines logged at warning level (one per warning: our messages are one line).
    int warnings() const {
        int n = 0;
        std::istringstream in(m_out.str());
        for (std::string line; std::getline(in, line);) n += line.rfind("warning|", 0) == 0;
        return n;
    }
    std::string text() const { return m_out.str(); }

  private:
    std::shared_ptr<spdlog::logger> m_previous;
    std::ostringstream m_out;
};

}  // namespace npt::test
