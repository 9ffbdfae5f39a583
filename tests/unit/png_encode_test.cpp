// core/png_encode: what it writes decodes (stb_image, an independent decoder) to exactly the bytes given, for
// grey, RGB and RGBA, odd sizes and content that exercises every Paeth predictor branch; bad sizes are errors.
#include <gtest/gtest.h>
#include <stb_image.h>

#include <vector>

#include "core/error.h"
#include "core/png_encode.h"
#include "core/rng.h"
#include "test_support.h"

namespace npt {
namespace {

TEST(PngEncode, DecodesToTheSameBytes) {
    const auto dir = test::temp_dir();
    Pcg32 rng(5, 6);
    for (int channels : {1, 3, 4})
        for (auto [w, h] : {std::pair{1, 1}, std::pair{7, 3}, std::pair{64, 33}}) {
            std::vector<uint8_t> px(size_t(w) * h * channels);
            // Half smooth gradients (small residuals), half noise (wrap-around residuals).
            for (size_t i = 0; i < px.size(); ++i)
                px[i] = i % 2 ? uint8_t(rng.next_u32()) : uint8_t((i / size_t(channels)) % size_t(w) * 3 + i % 5);
            const auto path = dir / ("p" + std::to_string(channels) + "_" + std::to_string(w) + ".png");
            encode_png(path, w, h, channels, px.data());
            int rw = 0, rh = 0, rc = 0;
            unsigned char* back = stbi_load(path.string().c_str(), &rw, &rh, &rc, channels);
            ASSERT_NE(back, nullptr) << path << ": " << stbi_failure_reason();
            EXPECT_EQ(rw, w);
            EXPECT_EQ(rh, h);
            EXPECT_EQ(rc, channels);
            EXPECT_EQ(std::vector<uint8_t>(back, back + px.size()), px) << channels << " channels, " << w << "x" << h;
            stbi_image_free(back);
        }
}

TEST(PngEncode, BadSizesAreErrors) {
    const auto dir = test::temp_dir();
    const uint8_t px[4] = {0, 0, 0, 0};
    EXPECT_THROW(encode_png(dir / "a.png", 0, 1, 3, px), Error);
    EXPECT_THROW(encode_png(dir / "b.png", 1, 1, 2, px), Error);
    EXPECT_THROW(encode_png(dir / "no_such_folder" / "c.png", 1, 1, 1, px), Error);
}

}  // namespace
}  // namespace npt
