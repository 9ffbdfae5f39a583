#include "interrupt.h"

#include <pthread.h>
#include <unistd.h>

#include <cstring>

namespace npt::cli {

InterruptGuard::InterruptGuard() {
    sigemptyset(&m_signals);
    sigaddset(&m_signals, SIGINT);
    sigaddset(&m_signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &m_signals, &m_old_mask);
    m_watcher = std::jthread([this](std::stop_token stop) { watch(stop); });
}

InterruptGuard::~InterruptGuard() {
    m_watcher.request_stop();
    // Wake the watcher from sigwait with a signal aimed at that thread only; it sees the stop request and
    // ends.
    pthread_kill(m_watcher.native_handle(), SIGTERM);
    m_watcher.join();
    pthread_sigmask(SIG_SETMASK, &m_old_mask, nullptr);
}

void InterruptGuard::watch(std::stop_token stop) {
    int sig = 0;
    while (sigwait(&m_signals, &sig) == 0) {
        if (stop.stop_requested()) return;
        if (m_cooperative && !m_stop_requested) {
            m_stop_signal = sig;
            m_stop_requested = true;
            const char* msg = "\nnerfpt: stopping after this step (interrupt again to quit at once)\n";
            [[maybe_unused]] auto n = write(STDERR_FILENO, msg, std::strlen(msg));
            continue;
        }
        std::unique_lock lock(m_mutex);  // let every file being written finish first
        // Only async-signal-safe calls from here on: other threads may be anywhere, so no exit handlers run.
        const char* msg = sig == SIGINT ? "\nnerfpt: interrupted\n" : "\nnerfpt: terminated\n";
        [[maybe_unused]] auto n = write(STDERR_FILENO, msg, std::strlen(msg));
        _exit(128 + sig);
    }
}

}  // namespace npt::cli
