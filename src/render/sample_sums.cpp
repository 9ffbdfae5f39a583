#include "render/sample_sums.h"

#include <cstring>
#include <string>
#include <type_traits>

#include "core/error.h"

namespace npt::render {

static_assert(sizeof(PixelSums) == 12 * sizeof(float) && std::is_trivially_copyable_v<PixelSums>,
              "PixelSums travels as bytes (partial_to_bytes)");

std::vector<SampleBlock> aligned_blocks(uint32_t begin, uint32_t end) {
    std::vector<SampleBlock> out;
    uint32_t p = begin;
    while (p < end) {
        uint32_t size =
            p == 0 ? 0x80000000u : (p & (~p + 1u));  // the largest power of two p is a multiple of
        while (size > end - p) size >>= 1;
        out.push_back({p, size});
        p += size;
    }
    return out;
}

void resolve_pixel(const PixelSums& sums, uint32_t spp, float* px, int channels, uint32_t aov_mask,
                   AovImages* aovs, size_t pixel) {
    px[0] = sums.radiance.x / float(spp);
    px[1] = sums.radiance.y / float(spp);
    px[2] = sums.radiance.z / float(spp);
    if (channels == 4) px[3] = 1.0f - sums.first.escaped / float(spp);
    if (aov_mask) {
        const FirstHitAovs a =
            resolve_first_hit(sums.first.weight, sums.first.albedo, sums.first.normal, sums.first.distance);
        aovs->set(pixel, a.albedo, a.normal, a.depth);
    }
}

namespace {

// The top two planes are siblings (one aligned block of twice the size): merge them.
bool merge_top(std::vector<PartialFilm::Plane>& planes) {
    if (planes.size() < 2) return false;
    PartialFilm::Plane& a = planes[planes.size() - 2];
    PartialFilm::Plane& b = planes.back();
    if (a.block.size != b.block.size || a.block.begin % (2 * a.block.size) != 0 ||
        a.block.end() != b.block.begin)
        return false;
    for (size_t i = 0; i < a.sums.size(); ++i) add_to(a.sums[i], b.sums[i]);
    a.block.size *= 2;
    planes.pop_back();
    return true;
}

}  // namespace

void merge_partial(PartialFilm& left, PartialFilm&& right) {
    if (right.planes.empty()) {
        left.dropped += right.dropped;
        return;
    }
    if (left.planes.empty()) {
        right.dropped += left.dropped;
        left = std::move(right);
        return;
    }
    if (left.width != right.width || left.height != right.height || left.spp != right.spp ||
        left.first_hits != right.first_hits || left.end() != right.begin())
        throw Error("merge_partial: the films are not neighbouring sample ranges of one render (samples " +
                    std::to_string(left.begin()) + ".." + std::to_string(left.end()) + " then " +
                    std::to_string(right.begin()) + ".." + std::to_string(right.end()) + ")");
    left.dropped += right.dropped;
    for (PartialFilm::Plane& p : right.planes) {
        left.planes.push_back(std::move(p));
        while (merge_top(left.planes)) {
        }
    }
}

Image resolve_partial(const PartialFilm& film, int channels, uint32_t aov_mask, AovImages* aovs) {
    if (film.begin() != 0 || film.end() != film.spp || film.planes.empty())
        throw Error("resolve_partial: the sums cover samples " + std::to_string(film.begin()) + ".." +
                    std::to_string(film.end()) + " of " + std::to_string(film.spp));
    // The planes left are the blocks of [0, spp) (every sibling pair was merged), as in one process.
    const std::vector<SampleBlock> expected = aligned_blocks(0, film.spp);
    bool same = expected.size() == film.planes.size();
    for (size_t b = 0; same && b < expected.size(); ++b) same = expected[b] == film.planes[b].block;
    if (!same)
        throw Error("resolve_partial: " + std::to_string(film.planes.size()) + " blocks left, not the " +
                    std::to_string(expected.size()) + " of " + std::to_string(film.spp) + " samples");
    Image image(film.width, film.height, channels);
    if (aov_mask) *aovs = make_aov_images(film.width, film.height, aov_mask);
    const size_t pixels = size_t(film.width) * size_t(film.height);
    for (size_t i = 0; i < pixels; ++i) {
        PixelSums acc = film.planes[0].sums[i];
        for (size_t b = 1; b < film.planes.size(); ++b) add_to(acc, film.planes[b].sums[i]);
        resolve_pixel(acc, film.spp, &image.pixels[i * size_t(channels)], channels, aov_mask, aovs, i);
    }
    return image;
}

namespace {

struct Header {
    char magic[8];
    int32_t width, height;
    uint32_t spp, first_hits, planes, pad;
    uint64_t dropped;
};
constexpr char k_magic[8] = {'N', 'P', 'T', 'S', 'U', 'M', 'S', '1'};

}  // namespace

std::vector<char> partial_to_bytes(const PartialFilm& film) {
    const size_t pixels = size_t(film.width) * size_t(film.height);
    const size_t per_pixel = film.first_hits ? sizeof(PixelSums) : sizeof(Rgb);
    std::vector<char> out(sizeof(Header) + film.planes.size() * (2 * sizeof(uint32_t) + pixels * per_pixel));
    Header h{};
    std::memcpy(h.magic, k_magic, sizeof k_magic);
    h.width = film.width;
    h.height = film.height;
    h.spp = film.spp;
    h.first_hits = film.first_hits ? 1 : 0;
    h.planes = uint32_t(film.planes.size());
    h.dropped = film.dropped;
    char* p = out.data();
    std::memcpy(p, &h, sizeof h);
    p += sizeof h;
    for (const PartialFilm::Plane& plane : film.planes) {
        std::memcpy(p, &plane.block.begin, sizeof(uint32_t));
        std::memcpy(p + sizeof(uint32_t), &plane.block.size, sizeof(uint32_t));
        p += 2 * sizeof(uint32_t);
        if (film.first_hits) {
            std::memcpy(p, plane.sums.data(), pixels * sizeof(PixelSums));
            p += pixels * sizeof(PixelSums);
        } else {
            for (size_t i = 0; i < pixels; ++i, p += sizeof(Rgb))
                std::memcpy(p, &plane.sums[i].radiance, sizeof(Rgb));
        }
    }
    return out;
}

PartialFilm partial_from_bytes(const std::vector<char>& bytes) {
    const auto bad = [](const std::string& why) { return Error("partial film message: " + why); };
    Header h{};
    if (bytes.size() < sizeof h) throw bad("shorter than its header");
    std::memcpy(&h, bytes.data(), sizeof h);
    if (std::memcmp(h.magic, k_magic, sizeof k_magic) != 0) throw bad("not a partial film");
    if (h.width < 1 || h.height < 1 || h.spp < 1 || h.first_hits > 1 || h.planes > 64)
        throw bad("bad header");
    const size_t pixels = size_t(h.width) * size_t(h.height);
    const size_t per_pixel = h.first_hits ? sizeof(PixelSums) : sizeof(Rgb);
    const size_t plane_bytes = 2 * sizeof(uint32_t) + pixels * per_pixel;
    if (bytes.size() != sizeof h + size_t(h.planes) * plane_bytes)
        throw bad("its size does not match its header");
    PartialFilm film;
    film.width = h.width;
    film.height = h.height;
    film.spp = h.spp;
    film.first_hits = h.first_hits != 0;
    film.dropped = h.dropped;
    const char* p = bytes.data() + sizeof h;
    for (uint32_t k = 0; k < h.planes; ++k) {
        PartialFilm::Plane plane;
        std::memcpy(&plane.block.begin, p, sizeof(uint32_t));
        std::memcpy(&plane.block.size, p + sizeof(uint32_t), sizeof(uint32_t));
        p += 2 * sizeof(uint32_t);
        const SampleBlock b = plane.block;
        if (b.size == 0 || (b.size & (b.size - 1)) != 0 || b.begin % b.size != 0 ||
            uint64_t(b.begin) + b.size > h.spp ||
            (!film.planes.empty() && film.planes.back().block.end() != b.begin))
            throw bad("block " + std::to_string(b.begin) + "+" + std::to_string(b.size) +
                      " is not an aligned block in order");
        plane.sums.resize(pixels);
        if (film.first_hits) {
            std::memcpy(plane.sums.data(), p, pixels * sizeof(PixelSums));
            p += pixels * sizeof(PixelSums);
        } else {
            for (size_t i = 0; i < pixels; ++i, p += sizeof(Rgb))
                std::memcpy(&plane.sums[i].radiance, p, sizeof(Rgb));
        }
        film.planes.push_back(std::move(plane));
    }
    return film;
}

}  // namespace npt::render
