#include "frame_writer.h"

#include <algorithm>
#include <thread>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>

namespace npt::cli {

namespace {
// Writing is background work: the rendering thread, which on a GPU launches many short kernels and waits on
// them, must not queue behind the writers' compression (nor behind OpenEXR's pool threads, which the first
// EXR write starts, on a writer thread, and so inherit its priority). Linux: nice applies per thread.
void lower_this_threads_priority() {
    errno = 0;
    const int now = getpriority(PRIO_PROCESS, pid_t(syscall(SYS_gettid)));
    if (errno == 0) (void)setpriority(PRIO_PROCESS, pid_t(syscall(SYS_gettid)), std::min(now + 10, 19));
}
}  // namespace

FrameWriter::FrameWriter(int max_in_flight, WrittenFn written)
    : m_max(std::max(1, max_in_flight)), m_written(std::move(written)) {}

FrameWriter::~FrameWriter() {
    for (Pending& p : m_pending)
        if (p.done.valid()) p.done.wait();
}

int FrameWriter::default_in_flight() {
    return std::clamp(int(std::thread::hardware_concurrency()) / 2, 1, 8);
}

void FrameWriter::submit(int frame, std::function<void()> write) {
    while (int(m_pending.size()) >= m_max) finish_oldest();
    m_pending.push_back({frame, std::async(std::launch::async, [w = std::move(write)] {
                             lower_this_threads_priority();
                             const auto t0 = std::chrono::steady_clock::now();
                             w();
                             return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                         })});
}

void FrameWriter::finish_all() {
    while (!m_pending.empty()) finish_oldest();
}

void FrameWriter::finish_oldest() {
    const auto t0 = std::chrono::steady_clock::now();
    Pending p = std::move(m_pending.front());
    m_pending.pop_front();
    const double write_s = p.done.get();  // rethrows the write's error
    m_waited += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (m_written) m_written(p.frame, write_s);
}

}  // namespace npt::cli
