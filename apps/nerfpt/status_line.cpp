#include "status_line.h"

#include <fmt/format.h>

#include <cstdio>

#include "core/progress.h"

namespace npt::cli {

bool StatusLine::due(bool force) {
    if (m_quiet) return false;
    const double now = Progress::steady_seconds();
    if (!force && now < m_next) return false;
    m_next = now + (m_tty ? 0.2 : 5.0);
    return true;
}

void StatusLine::print(const std::string& text) {
    if (m_tty) {
        fmt::print(stderr, "\r{}\x1b[K", text);
        m_open = true;
    } else {
        fmt::print(stderr, "{}\n", text);
    }
}

void StatusLine::finish() {
    if (m_open) fmt::print(stderr, "\n");
    m_open = false;
}

}  // namespace npt::cli
