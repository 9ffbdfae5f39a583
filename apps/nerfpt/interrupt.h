// Ctrl-C (SIGINT) and SIGTERM handling for the whole program. Signals are blocked in every thread and taken
// by one watcher thread, which prints a message and exits at once; while files are being written it waits
// until they are complete, so an interrupt never leaves a half-written output.
#pragma once

#include <signal.h>

#include <atomic>
#include <mutex>
#include <shared_mutex>
#include <thread>

namespace npt::cli {

class InterruptGuard {
  public:
    // Construct first in main(), before any other thread exists: threads inherit the blocked signal mask, so
    // the watcher is the only thread that ever sees SIGINT/SIGTERM.
    InterruptGuard();
    ~InterruptGuard();
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;

    // While the returned lock lives, an interrupt is held back (it takes effect when the lock is released).
    // Shared: several threads may each be writing a file (a shot's frame writers), and all of them finish.
    std::shared_lock<std::shared_mutex> hold() { return std::shared_lock(m_mutex); }

    // Work that can stop cleanly (training: save a checkpoint, then exit) turns this on: the first interrupt
    // then only sets stop_requested(); a second one exits at once as usual.
    void set_cooperative(bool on) { m_cooperative = on; }
    bool stop_requested() const { return m_stop_requested; }
    int stop_signal() const { return m_stop_signal; }

  private:
    void watch(std::stop_token stop);

    std::atomic<bool> m_cooperative{false};
    std::atomic<bool> m_stop_requested{false};
    std::atomic<int> m_stop_signal{0};
    sigset_t m_signals{};
    sigset_t m_old_mask{};
    std::shared_mutex m_mutex;
    std::jthread m_watcher;
};

}  // namespace npt::cli
