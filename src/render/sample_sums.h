// How a pixel's samples are added up, so that an image split over processes by sample index (MPI ranks, each
// with its own range of samples) is bitwise the image one process makes. Float addition is not associative,
// so the grouping is fixed by the sample indices alone, never by who rendered them: samples are added in a
// pairwise tree over aligned power-of-two blocks ([0,1) [1,2) -> [0,2), [0,2) [2,4) -> [0,4), ...), the tree
// a binary counter builds; the blocks of the whole range (the binary digits of spp, largest first) are then
// added left to right. A process with the samples [begin, end) keeps the maximal aligned blocks inside its
// range (at most 2 log2(spp) of them); adding neighbours' lists merges sibling blocks into their parents, so
// the reduction of all ranges in sample order rebuilds exactly the one-process tree, for any number of
// ranges and any split points.
#pragma once

#include <cstdint>
#include <vector>

#include "core/image.h"
#include "render/film.h"
#include "render/first_hit.h"

namespace npt::render {

// An aligned block of sample indices: size a power of two, begin a multiple of size.
struct SampleBlock {
    uint32_t begin = 0, size = 0;
    uint32_t end() const { return begin + size; }
    bool operator==(const SampleBlock&) const = default;
};

// The maximal aligned blocks covering [begin, end), in order (greedy: at each point the largest aligned block
// that fits). For [0, spp): the binary digits of spp, largest first.
std::vector<SampleBlock> aligned_blocks(uint32_t begin, uint32_t end);

// What a pixel sums over its samples: radiance and the first hits' records (render/first_hit.h).
struct PixelSums {
    Rgb radiance{0.0f};
    FirstHitSums first;
};
inline void add_to(PixelSums& a, const PixelSums& b) {
    a.radiance += b.radiance;
    a.first.escaped += b.first.escaped;
    a.first.weight += b.first.weight;
    a.first.albedo += b.first.albedo;
    a.first.normal += b.first.normal;
    a.first.distance += b.first.distance;
}

// The sum over the aligned block `b` of leaf(s) for s in b, in the pairwise tree of its indices.
template <class Leaf>
PixelSums sum_block(SampleBlock b, const Leaf& leaf) {
    PixelSums stack[33];
    int top = 0;
    for (uint32_t i = 0; i < b.size; ++i) {
        stack[top++] = leaf(b.begin + i);
        for (uint32_t k = i + 1; (k & 1u) == 0; k >>= 1) {  // a block of 2, 4, ... finished: merge its halves
            --top;
            add_to(stack[top - 1], stack[top]);
        }
    }
    return stack[0];
}

// The pixel's value from the sums of all `spp` samples: radiance / spp, alpha (channels 4) 1 - escaped / spp,
// and the AOVs of `aov_mask` into aovs at `pixel`. The one place both the one-process and the split renders
// turn sums into a film.
void resolve_pixel(const PixelSums& sums, uint32_t spp, float* px, int channels, uint32_t aov_mask,
                   AovImages* aovs, size_t pixel);

// The sums of one process's samples [begin, end) of a width x height film: one plane per aligned block.
struct PartialFilm {
    int width = 0, height = 0;
    uint32_t spp = 0;         // the whole render's samples per pixel
    bool first_hits = false;  // the planes' first-hit sums are meaningful (transparent or AOVs)
    uint64_t dropped = 0;     // NaN or infinite samples left out
    struct Plane {
        SampleBlock block;
        std::vector<PixelSums> sums;  // width * height
    };
    std::vector<Plane> planes;  // in sample order, contiguous
    uint32_t begin() const { return planes.empty() ? 0 : planes.front().block.begin; }
    uint32_t end() const { return planes.empty() ? 0 : planes.back().block.end(); }
};

// `right` (the samples just after left's) appended to `left`, sibling blocks merged into their parents (left
// + right, pixel by pixel). Throws npt::Error when the two are not neighbours of the same film.
void merge_partial(PartialFilm& left, PartialFilm&& right);

// The image (3 channels, or 4 with `channels` 4) and AOVs of a film whose planes cover [0, spp): throws
// npt::Error otherwise.
Image resolve_partial(const PartialFilm& film, int channels, uint32_t aov_mask, AovImages* aovs);

// A film as bytes for another process (same build, same byte order) and back: 12 bytes a pixel and plane
// without first hits, 48 with. from_bytes checks sizes and blocks (npt::Error on a bad message).
std::vector<char> partial_to_bytes(const PartialFilm& film);
PartialFilm partial_from_bytes(const std::vector<char>& bytes);

}  // namespace npt::render
