// Allocation failures as messages a user can act on: what was being allocated, how much, and what to lower.
// A bare std::bad_alloc says none of that. Used where an input's sizes or an option decide a large
// allocation.
#pragma once

#include <cstdio>
#include <new>
#include <string>

#include "core/error.h"

namespace npt {

// "512 B", "3.2 MiB", "17.2 GiB".
inline std::string format_bytes(double bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB"};
    int u = 0;
    while (bytes >= 1024.0 && u < 5) {
        bytes /= 1024.0;
        ++u;
    }
    char buf[32];
    std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.1f %s", bytes, units[u]);
    return buf;
}

// Runs fn() and rethrows std::bad_alloc as npt::Error "<what> needs <bytes> of memory, more than this machine
// could allocate: <hint>". `what` names the file or option ("lego/transforms.json: 300 frames of 800x800"),
// `hint` what to lower.
template <typename Fn>
decltype(auto) with_memory_context(const std::string& what, double bytes, const std::string& hint, Fn&& fn) {
    try {
        return fn();
    } catch (const std::bad_alloc&) {
        throw Error(what + " needs " + format_bytes(bytes) +
                    " of memory, more than this machine could allocate: " + hint);
    }
}

}  // namespace npt
