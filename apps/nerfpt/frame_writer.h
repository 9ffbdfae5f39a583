// A shot's frames are written while the next ones render: writing a 1080p float EXR and its PNG takes 0.6-1 s
// on one core, 30-50x a 1-spp GPU frame (docs/benchmarks.md, issue 26). Up to `max_in_flight` frames are written
// at once, each by its own thread; submit() waits for the oldest when that many are pending, and reports frames
// in the order they were submitted. A write that throws makes the next submit() or finish_all() throw.
#pragma once

#include <chrono>
#include <deque>
#include <functional>
#include <future>

namespace npt::cli {

class FrameWriter {
  public:
    // `written(frame, seconds)`: called on the submitting thread, in submission order, once a frame's files are
    // all written (when the writer next waits for it); seconds: how long its writing took.
    using WrittenFn = std::function<void(int frame, double seconds)>;
    FrameWriter(int max_in_flight, WrittenFn written);
    ~FrameWriter();  // waits for pending writes (their errors are dropped: finish_all() reports them)
    FrameWriter(const FrameWriter&) = delete;
    FrameWriter& operator=(const FrameWriter&) = delete;

    void submit(int frame, std::function<void()> write);
    void finish_all();
    double waited_seconds() const { return m_waited; }  // the submitting thread's time blocked on writers
    int max_in_flight() const { return m_max; }

    // Writers for a machine: half its hardware threads (the other half keeps rendering), 1 to 8.
    static int default_in_flight();

  private:
    struct Pending {
        int frame;
        std::future<double> done;  // the write's seconds
    };
    void finish_oldest();

    int m_max;
    WrittenFn m_written;
    std::deque<Pending> m_pending;
    double m_waited = 0.0;
};

}  // namespace npt::cli
