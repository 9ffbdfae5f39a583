// The fixed grouping of a pixel's samples (render/sample_sums.h): any split of [0, spp) into contiguous
// ranges, each summed alone and merged in sample order, gives bitwise the one-process sum; the CPU renderer's
// shares of a real render resolve to its own image byte for byte; the message format round-trips and refuses
// bad input.
#include "render/sample_sums.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "core/error.h"
#include "render/cpu/cpu_renderer.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt::render {
namespace {

TEST(SampleSums, AlignedBlocksAreMaximalAndCoverTheRange) {
    const auto blocks = [](uint32_t b, uint32_t e) {
        std::vector<std::pair<uint32_t, uint32_t>> out;
        for (const SampleBlock& s : aligned_blocks(b, e)) out.push_back({s.begin, s.size});
        return out;
    };
    using V = std::vector<std::pair<uint32_t, uint32_t>>;
    EXPECT_EQ(blocks(0, 13), (V{{0, 8}, {8, 4}, {12, 1}}));
    EXPECT_EQ(blocks(5, 13), (V{{5, 1}, {6, 2}, {8, 4}, {12, 1}}));
    EXPECT_EQ(blocks(0, 64), (V{{0, 64}}));
    EXPECT_TRUE(blocks(7, 7).empty());
    for (uint32_t b = 0; b < 70; ++b)
        for (uint32_t e = b; e < 70; ++e) {
            uint32_t p = b;
            for (const SampleBlock& s : aligned_blocks(b, e)) {
                ASSERT_EQ(s.begin, p);
                ASSERT_TRUE(s.size > 0 && (s.size & (s.size - 1)) == 0 && s.begin % s.size == 0);
                p = s.end();
            }
            ASSERT_EQ(p, e);
        }
}

// A film of `pixels` x 1 whose sample s of pixel i is leaf(i, s): the planes of [begin, end).
template <class Leaf>
PartialFilm partial(int pixels, uint32_t spp, uint32_t begin, uint32_t end, const Leaf& leaf) {
    PartialFilm f;
    f.width = pixels;
    f.height = 1;
    f.spp = spp;
    f.first_hits = true;
    for (const SampleBlock& b : aligned_blocks(begin, end)) {
        PartialFilm::Plane plane{b, std::vector<PixelSums>(size_t(pixels))};
        for (int i = 0; i < pixels; ++i)
            plane.sums[size_t(i)] = sum_block(b, [&](uint32_t s) { return leaf(i, s); });
        f.planes.push_back(std::move(plane));
    }
    f.dropped = end - begin;
    return f;
}

TEST(SampleSums, AnySplitMergedInOrderIsBitwiseTheOneProcessSum) {
    // Values over many orders of magnitude, so that a different grouping would change the sums' last bits.
    const auto leaf = [](int pixel, uint32_t s) {
        std::mt19937 rng(uint32_t(pixel) * 7919u + s);
        std::uniform_real_distribution<float> u(-8.0f, 8.0f);
        PixelSums v;
        v.radiance = Rgb(std::exp2(u(rng)), std::exp2(u(rng)), std::exp2(2.0f * u(rng)));
        v.first.escaped = std::exp2(u(rng));
        v.first.weight = std::exp2(u(rng));
        v.first.albedo = Rgb(std::exp2(u(rng)));
        v.first.normal = Vec3(u(rng), u(rng), u(rng));
        v.first.distance = std::exp2(u(rng));
        return v;
    };
    const int pixels = 5;
    const uint32_t mask = k_aov_albedo | k_aov_normal | k_aov_depth;
    std::mt19937 rng(1);
    int differs_from_sequential = 0;
    for (uint32_t spp : {1u, 2u, 3u, 7u, 13u, 64u, 100u, 257u}) {
        // One process: the blocks of [0, spp) folded left to right, as CpuFrameRenderer::render does.
        Image one(pixels, 1, 4);
        AovImages one_aovs = make_aov_images(pixels, 1, mask);
        const std::vector<SampleBlock> blocks = aligned_blocks(0, spp);
        for (int i = 0; i < pixels; ++i) {
            const auto l = [&](uint32_t s) { return leaf(i, s); };
            PixelSums acc = sum_block(blocks[0], l);
            for (size_t b = 1; b < blocks.size(); ++b) add_to(acc, sum_block(blocks[b], l));
            resolve_pixel(acc, spp, one.at(i, 0), 4, mask, &one_aovs, size_t(i));
            Rgb sequential(0.0f);
            for (uint32_t s = 0; s < spp; ++s) sequential += leaf(i, s).radiance;
            differs_from_sequential += sequential.x != acc.radiance.x;
        }
        for (int ranks : {1, 2, 3, 4, 7, 16}) {
            for (int trial = 0; trial < 4; ++trial) {
                // Split points: even for trial 0, random (some ranges empty) for the others.
                std::vector<uint32_t> cuts{0};
                for (int r = 1; r < ranks; ++r)
                    cuts.push_back(trial == 0 ? uint32_t(uint64_t(spp) * uint64_t(r) / uint64_t(ranks))
                                              : std::uniform_int_distribution<uint32_t>(0, spp)(rng));
                cuts.push_back(spp);
                std::sort(cuts.begin(), cuts.end());
                // Merged in rank order along a binomial tree, as MpiWorld::reduce_in_rank_order does.
                std::vector<PartialFilm> films;
                for (int r = 0; r < ranks; ++r)
                    films.push_back(partial(pixels, spp, cuts[size_t(r)], cuts[size_t(r) + 1], leaf));
                for (int step = 1; step < ranks; step *= 2)
                    for (int r = 0; r + step < ranks; r += 2 * step)
                        merge_partial(films[size_t(r)], std::move(films[size_t(r + step)]));
                AovImages aovs;
                const Image split = resolve_partial(films[0], 4, mask, &aovs);
                ASSERT_EQ(
                    0, std::memcmp(split.pixels.data(), one.pixels.data(), one.pixels.size() * sizeof(float)))
                    << spp << " spp over " << ranks << " ranges, trial " << trial;
                for (auto [a, b] : {std::pair{&aovs.albedo, &one_aovs.albedo},
                                    {&aovs.normal, &one_aovs.normal},
                                    {&aovs.depth, &one_aovs.depth}})
                    ASSERT_EQ(
                        0, std::memcmp(a->pixels.data(), b->pixels.data(), a->pixels.size() * sizeof(float)));
                EXPECT_EQ(films[0].dropped, spp);
            }
        }
    }
    EXPECT_GT(differs_from_sequential, 0) << "the test's values do not tell groupings apart";
}

TEST(SampleSums, MergeAndResolveRefuseGaps) {
    const auto leaf = [](int, uint32_t s) {
        PixelSums v;
        v.radiance = Rgb(float(s));
        return v;
    };
    PartialFilm a = partial(2, 10, 0, 4, leaf);
    test::expect_error_message([&] { merge_partial(a, partial(2, 10, 5, 10, leaf)); },
                               {"neighbouring", "5..10"});
    test::expect_error_message([&] { merge_partial(a, partial(3, 10, 4, 10, leaf)); }, {"neighbouring"});
    AovImages none;
    test::expect_error_message([&] { resolve_partial(a, 3, 0, &none); }, {"0..4 of 10"});
    merge_partial(a, partial(2, 10, 4, 10, leaf));
    const Image image = resolve_partial(a, 3, 0, &none);
    EXPECT_FLOAT_EQ(image.at(1, 0)[0], 4.5f);  // the mean of 0..9
}

TEST(SampleSums, BytesRoundTripAndBadMessagesAreRefused) {
    const auto leaf = [](int i, uint32_t s) {
        PixelSums v;
        v.radiance = Rgb(float(s), float(i), 0.5f);
        v.first.distance = float(s + 1);
        return v;
    };
    for (bool first_hits : {false, true}) {
        PartialFilm f = partial(3, 20, 3, 17, leaf);
        f.first_hits = first_hits;
        const PartialFilm back = partial_from_bytes(partial_to_bytes(f));
        ASSERT_EQ(back.planes.size(), f.planes.size());
        EXPECT_EQ(back.dropped, f.dropped);
        for (size_t p = 0; p < f.planes.size(); ++p) {
            EXPECT_EQ(back.planes[p].block, f.planes[p].block);
            for (size_t i = 0; i < 3; ++i) {
                EXPECT_EQ(back.planes[p].sums[i].radiance.x, f.planes[p].sums[i].radiance.x);
                EXPECT_EQ(back.planes[p].sums[i].first.distance,
                          first_hits ? f.planes[p].sums[i].first.distance : 0.0f);
            }
        }
    }
    const std::vector<char> good = partial_to_bytes(partial(3, 20, 3, 17, leaf));
    std::vector<char> cut(good.begin(), good.end() - 1);
    test::expect_error_message([&] { partial_from_bytes(cut); }, {"partial film", "size"});
    test::expect_error_message(
        [&] { partial_from_bytes(std::vector<char>(good.begin(), good.begin() + 10)); },
        {"partial film", "header"});
    std::vector<char> magic = good;
    magic[0] = 'X';
    test::expect_error_message([&] { partial_from_bytes(magic); }, {"not a partial film"});
    std::vector<char> misaligned = good;  // the first block, 3+1, said to start at 2
    const uint32_t two = 2;
    std::memcpy(misaligned.data() + 40, &two, sizeof two);
    test::expect_error_message([&] { partial_from_bytes(misaligned); }, {"not an aligned block"});
}

TEST(SampleSums, CpuRenderersSharesResolveToItsImage) {
    const scene::Scene scene =
        scene::load_scene(test::test_data().parent_path().parent_path() / "scenes" / "shot" / "scene.gltf");
    RenderOptions o;
    o.width = 20;
    o.height = 14;
    o.spp = 11;
    o.seed = 5;
    o.threads = 2;
    o.transparent = true;
    o.aovs = k_aov_albedo | k_aov_depth;
    const RenderOptions resolved = resolve_options(scene, o);
    cpu::CpuFrameRenderer renderer(scene, resolved.width, resolved.height);
    AovImages aovs;
    const Image one = renderer.render(resolved, {}, &aovs);
    PartialFilm merged = renderer.render_partial(resolved, 0, 3);
    merge_partial(merged, renderer.render_partial(resolved, 3, 4));
    merge_partial(merged, renderer.render_partial(resolved, 4, 11));
    AovImages split_aovs;
    const Image split = resolve_partial(merged, 4, resolved.aovs, &split_aovs);
    ASSERT_EQ(split.pixels.size(), one.pixels.size());
    EXPECT_EQ(0, std::memcmp(split.pixels.data(), one.pixels.data(), one.pixels.size() * sizeof(float)));
    EXPECT_EQ(0, std::memcmp(split_aovs.depth.pixels.data(), aovs.depth.pixels.data(),
                             aovs.depth.pixels.size() * sizeof(float)));
    EXPECT_EQ(0, std::memcmp(split_aovs.albedo.pixels.data(), aovs.albedo.pixels.data(),
                             aovs.albedo.pixels.size() * sizeof(float)));
    test::expect_error_message([&] { renderer.render_partial(resolved, 5, 12); }, {"5..12", "11"});
}

}  // namespace
}  // namespace npt::render
