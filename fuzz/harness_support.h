// What every harness shares: a private scratch folder (each fuzzing process its own, files relative to it so
// a fuzzed path cannot name another one), writing the input there, and the rule for what counts as a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace npt::fuzz {

// A folder under $TMPDIR made once per process and made the working directory, so that relative paths in a
// fuzzed file resolve inside it; with spdlog off (loaders warn a lot on garbage).
const std::filesystem::path& scratch();

// Writes bytes to scratch()/name and returns the path.
std::filesystem::path put(const std::string& name, const uint8_t* data, size_t size);
std::filesystem::path put(const std::string& name, std::string_view text);

// Runs a loader on fuzzed input: npt::Error is the expected way to refuse it. Anything else that escapes (a
// std::exception from a library, a crash, a sanitizer report, a hang) is a finding: the exception is
// rethrown, which libFuzzer reports as a crash with its input saved.
template <typename Fn>
void refuse_or_load(Fn&& fn);

}  // namespace npt::fuzz

#include "core/error.h"

template <typename Fn>
void npt::fuzz::refuse_or_load(Fn&& fn) {
    try {
        fn();
    } catch (const npt::Error&) {
    }
}
