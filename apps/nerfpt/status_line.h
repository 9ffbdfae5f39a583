// One status line for a CLI stage (training, the relight stage): redrawn in place on a terminal at most five
// times a second, a plain line every five seconds in a log or pipe. core/progress.h's Progress is for counted
// work with a rate; this one shows whatever text the stage composes.
#pragma once

#include <string>

namespace npt::cli {

class StatusLine {
  public:
    StatusLine(bool tty, bool quiet) : m_tty(tty), m_quiet(quiet) {}

    // True when a line should be shown now (always with `force`, never when quiet); starts the next interval.
    // Lets a caller skip composing text that would not be shown.
    bool due(bool force);
    // Shows `text` unconditionally (call when due()).
    void print(const std::string& text);
    // due() then print().
    void show(const std::string& text, bool force) {
        if (due(force)) print(text);
    }
    // Ends the terminal's line, if one is open. Idempotent.
    void finish();

  private:
    bool m_tty, m_quiet;
    bool m_open = false;
    double m_next = 0;
};

}  // namespace npt::cli
