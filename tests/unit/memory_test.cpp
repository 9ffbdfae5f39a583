// core/memory: an allocation an input or option decides fails with a message naming what, how much and what
// to lower, instead of a bare std::bad_alloc.
#include "core/memory.h"

#include <gtest/gtest.h>

#include <new>

#include "test_support.h"

namespace npt {
namespace {

TEST(Memory, BadAllocBecomesAnErrorNamingSizeAndHint) {
    EXPECT_EQ(format_bytes(512), "512 B");
    EXPECT_EQ(format_bytes(1.5 * 1024 * 1024), "1.5 MiB");
    EXPECT_EQ(format_bytes(20.0 * 1024 * 1024 * 1024), "20.0 GiB");
    test::expect_error_message(
        [] {
            with_memory_context("data/transforms.json: 300 frames of 8000x8000", 300.0 * 8000 * 8000 * 4,
                                "use fewer or smaller images", []() -> int { throw std::bad_alloc(); });
        },
        {"data/transforms.json: 300 frames of 8000x8000 needs 71.5 GiB", "use fewer or smaller images"});
    EXPECT_EQ(with_memory_context("x", 1, "y", [] { return 7; }), 7);
}

}  // namespace
}  // namespace npt
