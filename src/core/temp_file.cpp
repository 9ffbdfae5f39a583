#include "core/temp_file.h"

#include <unistd.h>

#include <cstdio>
#include <random>
#include <string>
#include <system_error>

#include "core/error.h"

namespace npt {

// Pid and a random number: two bakes writing into one folder never share a temporary name, and the rename
// stays within one file system, so it is atomic.
TempFile::TempFile(std::filesystem::path target) : m_target(std::move(target)) {
    std::random_device rd;
    m_temp = m_target.parent_path() / (m_target.filename().string() + ".tmp-" + std::to_string(getpid()) +
                                       "-" + std::to_string(rd() % 1000000));
}

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
