#include "capture/frame_source.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "core/executable.h"

namespace npt::capture {
namespace {

// A temporary file for a child's stderr, removed when the owner goes away.
std::filesystem::path temp_log_path(const char* what) {
    static int counter = 0;  // only distinguishes files within this process; the pid separates processes
    return std::filesystem::temp_directory_path() /
           fmt::format("nerfpt_{}_{}_{}.log", what, ::getpid(), counter++);
}

std::string first_line_of(const std::filesystem::path& file) {
    std::ifstream in(file);
    std::string line;
    while (std::getline(in, line)) {
        if (!line.empty()) return line;
    }
    return "no message";
}

std::string run_capture_stdout(const std::string& command, int& status) {
    std::FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) throw Error(fmt::format("could not start '{}'", command));
    std::string out;
    char buffer[4096];
    size_t n = 0;
    while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
    status = ::pclose(pipe);
    return out;
}

double parse_rate(const std::string& rate) {
    const size_t slash = rate.find('/');
    if (slash == std::string::npos) return std::atof(rate.c_str());
    const double num = std::atof(rate.substr(0, slash).c_str());
    const double den = std::atof(rate.substr(slash + 1).c_str());
    return den > 0.0 ? num / den : 0.0;
}

}  // namespace

std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) {
        if (c == '\'')
            q += "'\\''";
        else
            q += c;
    }
    return q + "'";
}

VideoInfo probe_video(const std::filesystem::path& video) {
    if (!std::filesystem::exists(video)) throw Error(fmt::format("{}: no such file", video.string()));
    if (find_executable("ffprobe").empty() || find_executable("ffmpeg").empty()) {
        throw Error(fmt::format("{}: ffmpeg/ffprobe not found on PATH; install ffmpeg (apt install ffmpeg)",
                                video.string()));
    }
    const std::filesystem::path log = temp_log_path("ffprobe");
    const std::string command = fmt::format(
        "ffprobe -v error -select_streams v:0 -show_entries "
        "stream=width,height,nb_frames,r_frame_rate,duration:stream_tags=rotate:stream_side_data=rotation "
        "-of json {} 2>{}",
        shell_quote(video.string()), shell_quote(log.string()));
    int status = 0;
    const std::string out = run_capture_stdout(command, status);
    const std::string err = first_line_of(log);
    std::filesystem::remove(log);
    nlohmann::json j = nlohmann::json::parse(out, nullptr, /*allow_exceptions=*/false);
    if (status != 0 || j.is_discarded() || !j.contains("streams") || j["streams"].empty()) {
        throw Error(fmt::format("{}: not a video (no video stream; ffprobe: {})", video.string(), err));
    }
    const nlohmann::json& s = j["streams"][0];
    VideoInfo info;
    info.width = s.value("width", 0);
    info.height = s.value("height", 0);
    info.fps = parse_rate(s.value("r_frame_rate", std::string("0")));
    if (s.contains("nb_frames")) info.frame_count = std::atoll(s["nb_frames"].get<std::string>().c_str());
    if (info.frame_count <= 0 && s.contains("duration") && info.fps > 0.0) {
        info.frame_count =
            int64_t(std::llround(std::atof(s["duration"].get<std::string>().c_str()) * info.fps));
    }
    // Rotation is either an old-style tag or display-matrix side data; ffmpeg's autorotation swaps the
    // size for quarter turns, so the raw frames we read have the swapped size.
    double rotation = 0.0;
    if (s.contains("tags") && s["tags"].contains("rotate")) {
        rotation = std::atof(s["tags"]["rotate"].get<std::string>().c_str());
    }
    if (s.contains("side_data_list")) {
        for (const auto& sd : s["side_data_list"]) {
            if (sd.contains("rotation") && sd["rotation"].is_number())
                rotation = sd["rotation"].get<double>();
        }
    }
    const int quarter = int(std::lround(rotation / 90.0)) % 2;
    if (quarter != 0) std::swap(info.width, info.height);
    if (info.width <= 0 || info.height <= 0 || info.width > 16384 || info.height > 16384) {
        throw Error(fmt::format("{}: video stream has an unusable size {}x{}", video.string(), info.width,
                                info.height));
    }
    if (info.fps <= 0.0) info.fps = 30.0;  // only used for timestamps in the report
    if (info.frame_count <= 0) throw Error(fmt::format("{}: video has zero frames", video.string()));
    return info;
}

FrameReader::FrameReader(const std::filesystem::path& video, const VideoInfo& info, int64_t step,
                         int64_t max_frames)
    : m_video(video), m_log(temp_log_path("ffmpeg")), m_info(info), m_step(std::max<int64_t>(1, step)) {
    // select keeps source frames n = 0, step, 2 step, ...; passthrough stops ffmpeg from duplicating
    // frames to restore the original rate (-vsync rather than -fps_mode: ffmpeg 4.x has only -vsync).
    const std::string filter = m_step > 1
                                   ? fmt::format("-vf {} -vsync passthrough ",
                                                 shell_quote(fmt::format("select=not(mod(n\\,{}))", m_step)))
                                   : std::string();
    const std::string command =
        fmt::format("ffmpeg -nostdin -v error -i {} {}-frames:v {} -f rawvideo -pix_fmt rgb24 - 2>{}",
                    shell_quote(video.string()), filter, max_frames, shell_quote(m_log.string()));
    m_pipe = ::popen(command.c_str(), "r");
    if (!m_pipe) throw Error(fmt::format("{}: could not start ffmpeg", video.string()));
}

FrameReader::~FrameReader() {
    if (m_pipe) ::pclose(m_pipe);
    std::error_code ec;
    std::filesystem::remove(m_log, ec);
}

void FrameReader::close_and_check() {
    const int status = ::pclose(m_pipe);
    m_pipe = nullptr;
    if (status != 0) {
        throw Error(
            fmt::format("{}: ffmpeg failed while decoding: {}", m_video.string(), first_line_of(m_log)));
    }
}

bool FrameReader::next(Frame8& frame) {
    if (!m_pipe) return false;
    frame.width = m_info.width;
    frame.height = m_info.height;
    frame.rgb.resize(size_t(frame.width) * size_t(frame.height) * 3);
    const size_t got = std::fread(frame.rgb.data(), 1, frame.rgb.size(), m_pipe);
    if (got == frame.rgb.size()) {
        ++m_returned;
        return true;
    }
    close_and_check();
    if (got != 0) {
        throw Error(
            fmt::format("{}: ffmpeg delivered a truncated frame ({} of {} bytes; the size {}x{} from "
                        "ffprobe does not match the decoded frames)",
                        m_video.string(), got, frame.rgb.size(), m_info.width, m_info.height));
    }
    return false;
}

}  // namespace npt::capture
