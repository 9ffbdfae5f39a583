#include "core/temp_file.h"

#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <system_error>

#include "core/error.h"

namespace npt {

int remove_stale_temporaries(const std::filesystem::path& target) {
    namespace fs = std::filesystem;
    const std::string prefix = target.filename().string() + ".tmp-";
    const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    std::error_code ec;
    fs::directory_iterator it(dir, ec), end;
    int removed = 0;
    for (; !ec && it != end; it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
        // The pid: the digits after ".tmp-", up to '-' or the end.
        size_t i = prefix.size();
        long long pid = 0;
        while (i < name.size() && name[i] >= '0' && name[i] <= '9' && pid < (1LL << 40))
            pid = pid * 10 + (name[i++] - '0');
        if (i == prefix.size() || (i < name.size() && name[i] != '-') || pid <= 0 || pid > INT32_MAX)
            continue;
        if (pid_t(pid) == ::getpid()) continue;
        if (::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;  // alive, or not ours to judge (EPERM)
        std::error_code rm;
        if (fs::is_regular_file(it->path(), rm) && fs::remove(it->path(), rm)) {
            ++removed;
            spdlog::info("removed {}: a temporary file left by process {}, which no longer runs",
                         it->path().string(), pid);
        }
    }
    return removed;
}

// Pid and a random number: two writers of one folder never share a temporary name, and the rename stays
// within one file system, so it is atomic. The pid also tells a stale temporary from a live one.
std::filesystem::path new_temp_path(const std::filesystem::path& target) {
    remove_stale_temporaries(target);
    std::random_device rd;
    return target.parent_path() / (target.filename().string() + ".tmp-" + std::to_string(getpid()) + "-" +
                                   std::to_string(rd() % 1000000));
}

TempFile::TempFile(std::filesystem::path target)
    : m_target(std::move(target)), m_temp(new_temp_path(m_target)) {}

TempFile::~TempFile() {
    if (m_committed) return;
    std::error_code ec;
    std::filesystem::remove(m_temp, ec);
}

void TempFile::commit() {
    std::error_code ec;
    std::filesystem::rename(m_temp, m_target, ec);
    if (ec) throw Error(m_target.string() + ": cannot write: " + ec.message());
    m_committed = true;
}

void write_text_atomic(const std::filesystem::path& path, std::string_view text) {
    TempFile tmp(path);
    std::FILE* f = std::fopen(tmp.path().c_str(), "wb");
    if (!f) throw Error(path.string() + ": cannot write (folder missing or not writable?)");
    const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size() && std::fflush(f) == 0 &&
                    ::fsync(::fileno(f)) == 0;
    if (std::fclose(f) != 0 || !ok) throw Error(path.string() + ": cannot write (disk full?)");
    tmp.commit();
}

}  // namespace npt
