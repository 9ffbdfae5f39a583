#include "core/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ostream>

namespace npt {

ProgressSettings::Style progress_style(bool is_tty, bool quiet) {
    if (quiet) return ProgressSettings::Style::Silent;
    return is_tty ? ProgressSettings::Style::Bar : ProgressSettings::Style::Lines;
}

bool stream_is_tty(std::FILE* stream) { return stream && isatty(fileno(stream)) == 1; }

std::string format_count(double v) {
    if (!std::isfinite(v) || v < 0) return "?";
    if (v < 1e3) return fmt::format("{:.0f}", v);
    if (v < 1e6) return fmt::format("{:.1f}k", v / 1e3);
    if (v < 1e9) return fmt::format("{:.1f}M", v / 1e6);
    return fmt::format("{:.1f}G", v / 1e9);
}

std::string format_eta_clock(double seconds) {
    if (!std::isfinite(seconds) || seconds < 0) return "?:??";
    auto s = static_cast<long long>(std::llround(seconds));
    if (s >= 3600) return fmt::format("{}:{:02}:{:02}", s / 3600, (s / 60) % 60, s % 60);
    return fmt::format("{}:{:02}", s / 60, s % 60);
}

std::string format_seconds(double seconds) {
    if (!std::isfinite(seconds) || seconds < 0) return "? s";
    if (seconds < 10) return fmt::format("{:.1f} s", seconds);
    auto s = static_cast<long long>(std::llround(seconds));
    if (s < 120) return fmt::format("{} s", s);
    if (s < 7200) return fmt::format("{} min {} s", s / 60, s % 60);
    return fmt::format("{} h {} min", s / 3600, (s / 60) % 60);
}

std::string format_bar(double fraction, int width) {
    fraction = std::clamp(std::isfinite(fraction) ? fraction : 0.0, 0.0, 1.0);
    const int filled = std::clamp(static_cast<int>(fraction * width), 0, width);
    std::string bar = "[";
    bar.append(size_t(filled), '#').append(size_t(width - filled), '.').push_back(']');
    return bar;
}

double Progress::steady_seconds() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

Progress::Progress(ProgressSettings settings, std::ostream& out, Clock clock)
    : m_settings(std::move(settings)), m_out(out), m_clock(std::move(clock)) {
    m_start = m_clock();
    // Lines wait a full interval before the first line: a run shorter than that prints only the final line.
    const bool lines = m_settings.style == ProgressSettings::Style::Lines;
    m_next_time.store(m_start + (lines ? m_settings.line_interval_s : 0.0));
}

Progress::~Progress() {
    // Interrupted by an exception: end the bar's line so that the error message starts on a fresh one.
    if (m_printed_bar && !m_finished) m_out << "\n" << std::flush;
}

void Progress::update(uint64_t done, uint64_t total) {
    if (m_settings.style == ProgressSettings::Style::Silent) return;
    m_seen_total.store(total, std::memory_order_relaxed);
    // The last update (done == total) is left to finish(), which prints 100% with the total time.
    if (done < m_next_done.load(std::memory_order_relaxed) || (total > 0 && done >= total)) return;
    const double now = m_clock();
    if (now < m_next_time.load(std::memory_order_relaxed)) return;
    std::unique_lock lock(m_print_mutex, std::try_to_lock);
    if (!lock.owns_lock() || m_finished) return;  // another thread is printing: this update is not needed
    print(done, total, now, false);
}

void Progress::finish() {
    std::lock_guard lock(m_print_mutex);
    if (m_finished || m_settings.style == ProgressSettings::Style::Silent) {
        m_finished = true;
        return;
    }
    // Finished means all the work is done, whichever thread's update came last.
    const uint64_t total = m_seen_total.load();
    print(total, total, m_clock(), true);
    m_finished = true;
}

void Progress::print(uint64_t done, uint64_t total, double now, bool final) {
    const double elapsed = now - m_start;
    if (m_settings.style == ProgressSettings::Style::Bar) {
        // \r returns to the line start, ESC[K clears what a longer previous line left behind.
        m_out << "\r" << line_text(done, total, elapsed, final) << "\x1b[K" << (final ? "\n" : "")
              << std::flush;
        m_printed_bar = true;
        m_next_time.store(now + m_settings.bar_interval_s, std::memory_order_relaxed);
        return;
    }
    m_out << line_text(done, total, elapsed, final) << "\n" << std::flush;
    m_next_time.store(now + m_settings.line_interval_s, std::memory_order_relaxed);
    if (total > 0 && m_settings.line_step > 0) {
        // The next line is due at the next multiple of line_step of the work.
        const double fraction = double(done) / double(total);
        const double next_fraction =
            (std::floor(fraction / m_settings.line_step + 1e-9) + 1.0) * m_settings.line_step;
        m_next_done.store(static_cast<uint64_t>(std::ceil(std::min(next_fraction, 1.0) * double(total))),
                          std::memory_order_relaxed);
    }
}

std::string Progress::line_text(uint64_t done, uint64_t total, double elapsed, bool final) const {
    const double fraction = total > 0 ? std::min(1.0, double(done) / double(total)) : (final ? 1.0 : 0.0);
    const int percent = static_cast<int>(std::floor(fraction * 100.0 + 1e-9));
    const double rate = elapsed > 0 ? double(done) / elapsed : NAN;
    const std::string rate_text =
        std::isfinite(rate) ? format_count(rate) + " " + m_settings.unit + "/s" : "";
    const double eta = rate > 0 ? double(total - std::min(done, total)) / rate : NAN;
    const std::string& label = m_settings.label;
    if (m_settings.style == ProgressSettings::Style::Bar) {
        std::string s =
            fmt::format("{} {} {:3}%", label, format_bar(fraction, m_settings.bar_width), percent);
        if (!rate_text.empty()) s += "  " + rate_text;
        s += final ? "  " + format_seconds(elapsed) : "  ETA " + format_eta_clock(eta);
        return s;
    }
    const std::string time = final ? format_seconds(elapsed) : "ETA " + format_seconds(eta);
    if (rate_text.empty()) return fmt::format("{}: {}% ({})", label, percent, time);
    return fmt::format("{}: {}% ({}, {})", label, percent, rate_text, time);
}

}  // namespace npt
