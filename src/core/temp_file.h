// A temporary sibling of an output file that is renamed over it on commit() and removed otherwise, so that
// readers never see a half-written file and a failed write leaves nothing behind.
#pragma once

#include <filesystem>
#include <string_view>

namespace npt {

// A fresh temporary name beside `target`: "<name>.tmp-<pid>-<random>" (every atomic writer uses this form).
// First removes the temporaries of `target` that a killed process left (SIGKILL, power loss): those whose pid
// names no running process. A temporary of a live process (another writer of the same file) is kept.
std::filesystem::path new_temp_path(const std::filesystem::path& target);

// The stale-temporary sweep alone; returns how many files it removed.
int remove_stale_temporaries(const std::filesystem::path& target);

class TempFile {
  public:
    explicit TempFile(std::filesystem::path target);
    ~TempFile();
    TempFile(const TempFile&) = delete;
    TempFile& operator=(const TempFile&) = delete;

    const std::filesystem::path& path() const { return m_temp; }
    // Renames the temporary file over the target; throws npt::Error naming the target when that fails.
    void commit();

  private:
    std::filesystem::path m_target, m_temp;
    bool m_committed = false;
};

// Writes `text` to `path` through a TempFile (data synced before the rename), so a crash or a full disk
// leaves the old file or none, never half of the new one. Throws npt::Error naming the file.
void write_text_atomic(const std::filesystem::path& path, std::string_view text);

}  // namespace npt
