// Image I/O: bit-exact EXR round trip, PNG quantisation bounds, atomic writes, and bad files that must fail
// with an npt::Error naming the file (never crash or allocate for absurd sizes).
#include "core/image_io.h"

#include <gtest/gtest.h>
#include <stb_image_write.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <random>

#include "core/error.h"
#include "test_support.h"

namespace npt {
namespace {

namespace fs = std::filesystem;

std::string read_all(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

size_t file_count(const fs::path& dir) {
    size_t n = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
    return n;
}

template <typename F>
void expect_image_error(F&& f, std::initializer_list<std::string> parts) {
    test::expect_error_message(std::forward<F>(f), parts);
}

TEST(ImageIo, SrgbCurvesAreInverse) {
    for (float v = 0.0f; v <= 1.0f; v += 1.0f / 64.0f)
        EXPECT_NEAR(srgb_to_linear(linear_to_srgb(v)), v, 1e-6f);
    EXPECT_FLOAT_EQ(srgb_to_linear(1.0f), 1.0f);
    EXPECT_NEAR(srgb_to_linear(0.5f), 0.2140411f, 1e-6f);
}

TEST(ImageIo, ExrRoundTripIsBitExact) {
    const fs::path dir = test::temp_dir();
    Image img(7, 5, 3);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-10.0f, 1000.0f);
    for (auto& v : img.pixels) v = u(rng);
    img.pixels[0] = 1e-30f;  // denormal-range values survive float32 storage too
    write_exr(dir / "out.exr", img);
    EXPECT_EQ(file_count(dir), 1u);  // the temporary file was renamed, nothing left beside it
    Image back = read_image(dir / "out.exr");
    ASSERT_EQ(back.width, 7);
    ASSERT_EQ(back.height, 5);
    ASSERT_EQ(back.channels, 3);
    EXPECT_EQ(std::memcmp(back.pixels.data(), img.pixels.data(), img.pixels.size() * sizeof(float)), 0);

    // RGBA input: alpha is dropped, RGB kept exactly; overwriting an existing file works.
    Image rgba(2, 2, 4);
    for (size_t i = 0; i < rgba.pixels.size(); ++i) rgba.pixels[i] = float(i) * 0.25f;
    write_exr(dir / "out.exr", rgba);
    Image back4 = read_image(dir / "out.exr");
    ASSERT_EQ(back4.channels, 3);
    EXPECT_EQ(back4.rgb(1, 1).x, rgba.rgb(1, 1).x);
    EXPECT_EQ(back4.rgb(1, 1).z, rgba.rgb(1, 1).z);
    EXPECT_EQ(file_count(dir), 1u);
}

// RGBA with named layers (nerfpt render --transparent --aov): read_image takes R, G, B, A back exactly; a one-channel
// Y file (OUT.depth.exr) reads as grey; a layer that does not fit the image is an error naming it.
TEST(ImageIo, ExrLayersAlphaAndLumaRoundTrip) {
    const fs::path dir = test::temp_dir();
    Image rgba(3, 2, 4), layer(3, 2, 3), depth(3, 2, 1);
    for (size_t i = 0; i < rgba.pixels.size(); ++i) rgba.pixels[i] = 0.1f * float(i);
    for (size_t i = 0; i < layer.pixels.size(); ++i) layer.pixels[i] = -float(i);
    for (size_t i = 0; i < depth.pixels.size(); ++i) depth.pixels[i] = 2.0f + float(i);
    write_exr_layers(dir / "l.exr", rgba, {{{"normal.X", "normal.Y", "normal.Z"}, &layer}, {{"depth.Z"}, &depth}});
    const Image back = read_image(dir / "l.exr");
    ASSERT_EQ(back.channels, 4);
    EXPECT_EQ(back.pixels, rgba.pixels);
    write_exr_channels(dir / "y.exr", depth, {"Y"});
    const Image grey = read_image(dir / "y.exr");
    ASSERT_EQ(grey.channels, 3);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(grey.at(2, 1)[c], depth.at(2, 1)[0]);
    const Image small(2, 2, 3);
    test::expect_error_message([&] { write_exr_layers(dir / "bad.exr", rgba, {{{"albedo.R", "albedo.G", "albedo.B"}, &small}}); },
                               {"bad.exr", "albedo.R"});
    EXPECT_FALSE(fs::exists(dir / "bad.exr"));
}

// Premultiplied RGBA to an RGBA PNG: the colour divided by alpha (straight, as PNG stores it), alpha kept.
TEST(ImageIo, PngFromPremultipliedAlphaIsStraight) {
    const fs::path dir = test::temp_dir();
    Image rgba(2, 1, 4);
    const float px[8] = {0.1f, 0.2f, 0.05f, 0.5f, 0.0f, 0.0f, 0.0f, 0.0f};
    std::copy(px, px + 8, rgba.pixels.begin());
    write_png_premultiplied(dir / "a.png", rgba);
    const Image back = read_image(dir / "a.png");  // sRGB-decoded
    ASSERT_EQ(back.channels, 4);
    EXPECT_NEAR(back.at(0, 0)[0], 0.2f, 0.01f);
    EXPECT_NEAR(back.at(0, 0)[1], 0.4f, 0.01f);
    EXPECT_NEAR(back.at(0, 0)[3], 0.5f, 1.0f / 255.0f);
    EXPECT_EQ(back.at(1, 0)[3], 0.0f);
    EXPECT_EQ(back.at(1, 0)[0], 0.0f);
}

TEST(ImageIo, PngGradientRoundTripWithinQuantisation) {
    const fs::path dir = test::temp_dir();
    Image img(256, 2, 3);
    for (int x = 0; x < 256; ++x)
        for (int c = 0; c < 3; ++c) {
            img.at(x, 0)[c] = float(x) / 255.0f;         // linear gradient
            img.at(x, 1)[c] = float(x) / 255.0f * 4.0f;  // overexposed half clamps to 1
        }
    write_png(dir / "g.png", img);
    EXPECT_EQ(file_count(dir), 1u);
    Image back = read_image(dir / "g.png");  // sRGB-decoded to linear
    ASSERT_EQ(back.width, 256);
    for (int x = 0; x < 256; ++x) {
        const float v = float(x) / 255.0f;
        // The 8-bit code is round(255 * srgb(v)), so in sRGB space the error is at most half a step.
        EXPECT_NEAR(linear_to_srgb(back.at(x, 0)[0]), linear_to_srgb(v), 0.5f / 255.0f + 1e-6f) << x;
        EXPECT_NEAR(back.at(x, 1)[1], std::min(v * 4.0f, 1.0f), 1.0f / 255.0f) << x;
    }
    // Exposure in stops: +2 stops of the gradient equals the x4 row.
    write_png(dir / "e.png", img, 2.0f);
    Image exposed = read_image(dir / "e.png");
    for (int x = 0; x < 256; ++x) EXPECT_EQ(exposed.at(x, 0)[0], back.at(x, 1)[0]) << x;
}

TEST(ImageIo, HdrIsLinear) {
    const fs::path dir = test::temp_dir();
    const float px[6] = {0.5f, 2.0f, 8.0f, 0.25f, 0.125f, 16.0f};
    ASSERT_TRUE(stbi_write_hdr((dir / "e.hdr").string().c_str(), 2, 1, 3, px));
    Image img = read_image(dir / "e.hdr");
    ASSERT_EQ(img.width, 2);
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(img.pixels[size_t(i)], px[i], px[i] * 0.01f);
}

TEST(ImageIoBadInput, MissingFile) {
    const fs::path dir = test::temp_dir();
    expect_image_error([&] { read_image(dir / "none.png"); }, {"none.png", "not found"});
    expect_image_error([&] { read_image(dir / "none.exr"); }, {"none.exr", "not found"});
}

TEST(ImageIoBadInput, EmptyAndTruncatedPng) {
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "empty.png", "");
    expect_image_error([&] { read_image(dir / "empty.png"); }, {"empty.png"});
    Image img(16, 16, 3);
    write_png(dir / "full.png", img);
    const std::string bytes = read_all(dir / "full.png");
    test::write_file(dir / "cut.png", bytes.substr(0, bytes.size() / 2));
    expect_image_error([&] { read_image(dir / "cut.png"); }, {"cut.png"});
    test::write_file(dir / "header.png", bytes.substr(0, 20));
    expect_image_error([&] { read_image(dir / "header.png"); }, {"header.png"});
}

TEST(ImageIo, SizeFromTheHeaderAlone) {
    const fs::path dir = test::temp_dir();
    write_png(dir / "f.png", Image(24, 10, 3));
    const ImageSize size = read_image_size(dir / "f.png");
    EXPECT_EQ(size.width, 24);
    EXPECT_EQ(size.height, 10);
    // The header is enough: a PNG cut after it still tells its size.
    const std::string bytes = read_all(dir / "f.png");
    test::write_file(dir / "cut.png", bytes.substr(0, 40));
    EXPECT_EQ(read_image_size(dir / "cut.png").width, 24);
    expect_image_error([&] { read_image_size(dir / "none.png"); }, {"none.png", "not found"});
    test::write_file(dir / "empty.png", "");
    expect_image_error([&] { read_image_size(dir / "empty.png"); }, {"empty.png"});
    std::vector<unsigned char> row(40000 * 3, 0);
    ASSERT_TRUE(stbi_write_png((dir / "wide.png").string().c_str(), 40000, 1, 3, row.data(), 40000 * 3));
    expect_image_error([&] { read_image_size(dir / "wide.png"); }, {"wide.png", "40000x1", "limit"});
}

TEST(ImageIoBadInput, TruncatedExr) {
    const fs::path dir = test::temp_dir();
    Image img(32, 32, 3);
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = float(i);
    write_exr(dir / "full.exr", img);
    const std::string bytes = read_all(dir / "full.exr");
    for (size_t cut : {size_t(4), size_t(40), bytes.size() / 2, bytes.size() - 8}) {
        const fs::path p = dir / ("cut" + std::to_string(cut) + ".exr");
        test::write_file(p, bytes.substr(0, cut));
        expect_image_error([&] { read_image(p); }, {p.filename().string()});
    }
}

TEST(ImageIoBadInput, ZeroAndAbsurdSizes) {
    const fs::path dir = test::temp_dir();
    expect_image_error([&] { write_png(dir / "zero.png", Image(0, 0, 3)); }, {"zero.png", "0x0"});
    expect_image_error([&] { write_exr(dir / "zero.exr", Image(0, 0, 3)); }, {"zero.exr", "0x0"});
    EXPECT_EQ(file_count(dir), 0u);
    // A valid PNG wider than the limit is rejected from its header, before decoding.
    std::vector<unsigned char> row(40000 * 3, 0);
    ASSERT_TRUE(stbi_write_png((dir / "wide.png").string().c_str(), 40000, 1, 3, row.data(), 40000 * 3));
    expect_image_error([&] { read_image(dir / "wide.png"); }, {"wide.png", "40000x1", "limit"});
    // An EXR header claiming a data window of 10^6 x 10^6 pixels.
    Image small(4, 4, 3);
    write_exr(dir / "huge.exr", small);
    std::string bytes = read_all(dir / "huge.exr");
    const std::string key = std::string("dataWindow") + '\0' + "box2i" + '\0';
    const size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    const int32_t box[4] = {0, 0, 999999, 999999};
    std::memcpy(&bytes[at + key.size() + 4], box, sizeof(box));
    test::write_file(dir / "huge.exr", bytes);
    expect_image_error([&] { read_image(dir / "huge.exr"); }, {"huge.exr"});
}

// An attribute whose size reaches past the end of the file is refused before OpenEXR allocates that size (it
// would: up to 2 GB from a 300-byte file; fuzz_image spent 93% of its time zero-filling such buffers).
TEST(ImageIoBadInput, ExrAttributeSizePastTheEnd) {
    const fs::path dir = test::temp_dir();
    write_exr(dir / "ok.exr", Image(4, 4, 3));
    const std::string bytes = read_all(dir / "ok.exr");
    const std::string key = std::string("channels") + '\0' + "chlist" + '\0';
    const size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    for (const int32_t size : {int32_t(0x7fffffff), int32_t(-5), int32_t(bytes.size())}) {
        std::string bad = bytes;
        std::memcpy(&bad[at + key.size()], &size, sizeof size);
        test::write_file(dir / "bad.exr", bad);
        expect_image_error([&] { read_image(dir / "bad.exr"); }, {"bad.exr", "'channels'", "claims"});
    }
    // A name without its terminating null within 31 characters.
    std::string long_name = bytes.substr(0, 8) + std::string(40, 'x');
    test::write_file(dir / "long.exr", long_name);
    expect_image_error([&] { read_image(dir / "long.exr"); }, {"long.exr", "longer than 31"});
    // Sizes inside the file that disagree with the value's layout (fuzz_image: a channel list whose records take
    // 63 bytes where the file says 55 put OpenEXR out of step; it then asked for 1.7 GB): a channel list stated
    // shorter than its records, and a fixed-size value (box2i, 16 bytes) stated longer.
    std::string short_list = bytes;
    int32_t listed = 0;
    std::memcpy(&listed, &short_list[at + key.size()], sizeof listed);
    const int32_t shorter = listed - 8;
    std::memcpy(&short_list[at + key.size()], &shorter, sizeof shorter);
    test::write_file(dir / "short_list.exr", short_list);
    expect_image_error([&] { read_image(dir / "short_list.exr"); }, {"short_list.exr", "'channels'", "contents"});
    const std::string box_key = std::string("dataWindow") + '\0' + "box2i" + '\0';
    const size_t box_at = bytes.find(box_key);
    ASSERT_NE(box_at, std::string::npos);
    std::string long_box = bytes;
    const int32_t box_size = 20;
    std::memcpy(&long_box[box_at + box_key.size()], &box_size, sizeof box_size);
    test::write_file(dir / "long_box.exr", long_box);
    expect_image_error([&] { read_image(dir / "long_box.exr"); }, {"long_box.exr", "'dataWindow'", "a box2i has 16"});
    // The valid file still reads.
    EXPECT_EQ(read_image(dir / "ok.exr").width, 4);
}

TEST(ImageIoBadInput, UnwritableFolder) {
    const fs::path dir = test::temp_dir() / "no" / "such" / "folder";
    expect_image_error([&] { write_png(dir / "x.png", Image(2, 2, 3)); }, {"x.png"});
    expect_image_error([&] { write_exr(dir / "x.exr", Image(2, 2, 3)); }, {"x.exr"});
}

}  // namespace
}  // namespace npt
