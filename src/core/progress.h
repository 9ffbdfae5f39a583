// Progress reporting for long work (rendering, later training and baking). On a terminal it redraws one bar
// in place; in a log or pipe it prints plain lines, rarely enough that a long run does not flood the log.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <iosfwd>
#include <mutex>
#include <string>

namespace npt {

struct ProgressSettings {
    std::string label = "render";  // first word of every line
    std::string unit = "samples";  // what `done` counts, for the rate
    enum class Style { Bar, Lines, Silent } style = Style::Lines;
    double bar_interval_s = 0.1;   // Bar: redraw at most this often (a terminal needs no more than ~10 Hz)
    double line_interval_s = 2.0;  // Lines: at most one line per this many seconds ...
    double line_step = 0.1;        // ... and per this fraction of the work, so short runs print few lines too
    int bar_width = 30;
};

// Bar on a terminal, Lines otherwise, Silent when quiet. `is_tty` is isatty() of the stream progress goes to.
ProgressSettings::Style progress_style(bool is_tty, bool quiet);
// True when the C stream is a terminal (e.g. stderr).
bool stream_is_tty(std::FILE* stream);

// Text helpers, exposed for tests.
std::string format_count(double v);                  // 1234 -> "1.2k", 1.5e6 -> "1.5M"
std::string format_eta_clock(double seconds);        // 12 -> "0:12", 3725 -> "1:02:05"
std::string format_seconds(double seconds);          // 12.3 -> "12 s", 0.4 -> "0.4 s", 150 -> "2 min 30 s"
std::string format_bar(double fraction, int width);  // "[#####.....]"

class Progress {
  public:
    using Clock = std::function<double()>;  // monotonic seconds; injectable so tests control time

    Progress(ProgressSettings settings, std::ostream& out, Clock clock = steady_seconds);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    // Thread-safe and cheap: when nothing is due it costs a clock read and two atomic loads, and it never
    // waits for another thread that is printing.
    void update(uint64_t done, uint64_t total);
    // Prints the final state (100% and the average rate) and ends the bar's line. Idempotent.
    void finish();

    static double steady_seconds();

  private:
    void print(uint64_t done, uint64_t total, double now, bool final);
    std::string line_text(uint64_t done, uint64_t total, double elapsed, bool final) const;

    ProgressSettings m_settings;
    std::ostream& m_out;
    Clock m_clock;
    double m_start = 0.0;
    // Fast-path gates: update() prints only when the clock has reached m_next_time and done has reached
    // m_next_done.
    std::atomic<double> m_next_time{0.0};
    std::atomic<uint64_t> m_next_done{0};
    // The latest total, for finish(), even when no update printed.
    std::atomic<uint64_t> m_seen_total{0};
    std::mutex m_print_mutex;
    bool m_finished = false;
    bool m_printed_bar = false;
};

}  // namespace npt
