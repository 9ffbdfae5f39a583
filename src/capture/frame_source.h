// Video frames for the curate stage, decoded by the `ffmpeg` command-line tool and read as raw RGB from a
// pipe: no OpenCV dependency and no temporary image files. ffmpeg autorotates phone videos, so frames come
// out upright and the probe reports the displayed (rotated) size.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace npt::capture {

// An 8-bit sRGB frame, row 0 at the top, RGB interleaved.
struct Frame8 {
    int width = 0;
    int height = 0;
    std::vector<uint8_t> rgb;  // width * height * 3
    const uint8_t* at(int x, int y) const { return &rgb[(size_t(y) * size_t(width) + size_t(x)) * 3]; }
};

struct VideoInfo {
    int width = 0;  // displayed size, after rotation metadata is applied
    int height = 0;
    double fps = 0.0;
    int64_t frame_count = 0;  // from the container, or duration x fps when the container does not say
};

// Runs ffprobe on the file. Throws npt::Error naming the file when ffprobe is missing, the file is not a
// video, or it has no frames.
VideoInfo probe_video(const std::filesystem::path& video);

// Decodes every `step`-th frame (0, step, 2 step, ...), at most `max_frames` of them, in order.
class FrameReader {
  public:
    FrameReader(const std::filesystem::path& video, const VideoInfo& info, int64_t step, int64_t max_frames);
    ~FrameReader();
    FrameReader(const FrameReader&) = delete;
    FrameReader& operator=(const FrameReader&) = delete;

    // Fills `frame` with the next frame; false at the end of the stream. Throws npt::Error when ffmpeg
    // fails (its first error line is in the message).
    bool next(Frame8& frame);
    // The index in the video of the frame last returned by next().
    int64_t source_index() const { return (m_returned - 1) * m_step; }

  private:
    void close_and_check();

    std::filesystem::path m_video;
    std::filesystem::path m_log;  // ffmpeg's stderr, read back for error messages
    VideoInfo m_info;
    int64_t m_step = 1;
    int64_t m_returned = 0;
    std::FILE* m_pipe = nullptr;
};

// Quotes a string for /bin/sh (single quotes, embedded quotes escaped).
std::string shell_quote(const std::string& s);

}  // namespace npt::capture
