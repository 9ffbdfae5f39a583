// The .npt model file: tagged sections behind a magic and a version, a checksum at the end, written through a
// temporary file and a rename. Arrays go straight between the file and the model's vectors in large chunks,
// each hashed while it is hot in the cache, so a 300 MB model is never copied whole.
#include "nerf/model_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/json_file.h"
#include "core/temp_file.h"
#include "nerf/relight/relight_section.h"

namespace npt::nerf {

static_assert(std::endian::native == std::endian::little, "the model file is little-endian: add byte swaps");
static_assert(sizeof(npt::Rgb) == 12, "EXPO stores Rgb as three floats");

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr char k_magic[8] = {'N', 'P', 'T', 'N', 'E', 'R', 'F', '1'};
constexpr uint32_t k_version = 1;
constexpr size_t k_chunk =
    size_t(8) << 20;                     // large enough for full disk speed, small enough to stay in cache
constexpr size_t k_section_header = 12;  // 4-byte tag + u64 payload length
constexpr uint64_t k_scen_bytes = 4 + 16 * 8;

// The checksum: one 64-bit word at a time (little-endian; the last partial word zero-padded), each word
// scrambled by an odd multiply and an xor-shift and then mixed into the state the same way; the byte count
// is mixed in last (so that padding zeros differ from stored zeros) and murmur3's finaliser spreads every
// bit. Every step is a bijection of the state for a fixed word, so any change confined to one word always
// changes the result. Not cryptographic: it catches disk and transfer corruption, not tampering.
constexpr uint64_t k_hash_seed = 0x6A09E667F3BCC909ull;
constexpr uint64_t k_hash_word_mul = 0x9E3779B97F4A7C15ull;
constexpr uint64_t k_hash_state_mul = 0xD6E8FEB86659FD93ull;

inline uint64_t hash_absorb(uint64_t h, uint64_t w) {
    w *= k_hash_word_mul;
    w ^= w >> 32;
    h = (h ^ w) * k_hash_state_mul;
    return h ^ (h >> 29);
}

class Hasher {
  public:
    void update(const void* data, size_t n) {
        const auto* p = static_cast<const uint8_t*>(data);
        m_length += n;
        if (m_tail_len > 0) {
            const size_t take = std::min(n, 8 - m_tail_len);
            std::memcpy(m_tail + m_tail_len, p, take);
            m_tail_len += take;
            p += take;
            n -= take;
            if (m_tail_len < 8) return;
            m_state = hash_absorb(m_state, load(m_tail));
            m_tail_len = 0;
        }
        uint64_t h = m_state;
        for (; n >= 8; p += 8, n -= 8) h = hash_absorb(h, load(p));
        m_state = h;
        std::memcpy(m_tail, p, n);
        m_tail_len = n;
    }

    uint64_t finish() const {
        uint64_t h = m_state;
        if (m_tail_len > 0) {
            uint8_t last[8] = {};
            std::memcpy(last, m_tail, m_tail_len);
            h = hash_absorb(h, load(last));
        }
        h = hash_absorb(h, m_length);
        h ^= h >> 33;
        h *= 0xFF51AFD7ED558CCDull;
        h ^= h >> 33;
        h *= 0xC4CEB9FE1A85EC53ull;
        return h ^ (h >> 33);
    }

  private:
    static uint64_t load(const uint8_t* p) {
        uint64_t w;
        std::memcpy(&w, p, 8);
        return w;
    }

    uint64_t m_state = k_hash_seed;
    uint64_t m_length = 0;
    uint8_t m_tail[8] = {};
    size_t m_tail_len = 0;
};

std::string errno_text(int err) { return std::strerror(err); }

size_t first_non_finite(const std::vector<float>& x) {
    for (size_t i = 0; i < x.size(); ++i)
        if (!std::isfinite(x[i])) return i;
    return x.size();
}

// Writes the temporary file; its destructor removes it unless commit() renamed it into place.
class AtomicWriter {
  public:
    explicit AtomicWriter(const fs::path& path)
        : m_path(path), m_tmp(path.string() + ".tmp-" + std::to_string(::getpid())) {
        remove_stale_temporaries(path);  // of killed writers (core/temp_file.h)
        m_file = std::fopen(m_tmp.c_str(), "wb");
        if (!m_file)
            throw Error(m_path.string() + ": cannot create the temporary file " + m_tmp.string() + " (" +
                        errno_text(errno) + ")");
    }
    ~AtomicWriter() {
        if (m_file) std::fclose(m_file);
        if (!m_committed) {
            std::error_code ec;
            fs::remove(m_tmp, ec);
        }
    }
    AtomicWriter(const AtomicWriter&) = delete;
    AtomicWriter& operator=(const AtomicWriter&) = delete;

    void write(const void* data, size_t n) {
        const auto* p = static_cast<const uint8_t*>(data);
        for (size_t done = 0; done < n;) {
            const size_t len = std::min(k_chunk, n - done);
            m_hash.update(p + done, len);
            if (std::fwrite(p + done, 1, len, m_file) != len) fail("cannot write");
            done += len;
        }
    }
    template <typename T>
    void put(T value) {
        write(&value, sizeof(T));
    }
    void section(const char (&tag)[5], uint64_t length) {
        write(tag, 4);
        put(length);
    }
    uint64_t hash() const { return m_hash.finish(); }

    // Data on disk first, then the rename, then the folder entry on disk: a crash at any point leaves either
    // the old file or the complete new one.
    void commit(uint64_t checksum) {
        section("CKSM", 8);
        put(checksum);
        if (std::fflush(m_file) != 0) fail("cannot write");
        if (::fsync(::fileno(m_file)) != 0) fail("cannot sync");
        const int closed = std::fclose(m_file);
        m_file = nullptr;
        if (closed != 0) fail("cannot write");
        std::error_code ec;
        fs::rename(m_tmp, m_path, ec);
        if (ec)
            throw Error(m_path.string() + ": cannot replace it with " + m_tmp.string() + " (" + ec.message() +
                        ")");
        m_committed = true;
        const fs::path folder = m_path.has_parent_path() ? m_path.parent_path() : fs::path(".");
        const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY);
        // Some file systems cannot sync a folder (EINVAL); the file itself is already safe there.
        if (fd >= 0) {
            const int synced = ::fsync(fd);
            const int err = errno;
            ::close(fd);
            if (synced != 0 && err != EINVAL)
                throw Error(m_path.string() + ": written, but its folder could not be synced (" +
                            errno_text(err) + ")");
        }
    }

  private:
    [[noreturn]] void fail(const char* what) const {
        throw Error(m_path.string() + ": " + what + " the model file (" + errno_text(errno) + ")");
    }

    fs::path m_path, m_tmp;
    std::FILE* m_file = nullptr;
    Hasher m_hash;
    bool m_committed = false;
};

// Reads the file front to back, hashing what it reads, and checks every length against what is left before
// allocating (a corrupt length cannot ask for 100 GB).
class Reader {
  public:
    explicit Reader(const fs::path& path) : m_name(path.string()) {
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) throw Error(m_name + ": file not found");
        m_size = fs::file_size(path, ec);
        if (ec) throw Error(m_name + ": cannot read file (" + ec.message() + ")");
        m_file = std::fopen(path.c_str(), "rb");
        if (!m_file) throw Error(m_name + ": cannot open (" + errno_text(errno) + ")");
    }
    ~Reader() { std::fclose(m_file); }
    Reader(const Reader&) = delete;
    Reader& operator=(const Reader&) = delete;

    uint64_t size() const { return m_size; }
    uint64_t remaining() const { return m_size - m_pos; }
    const std::string& name() const { return m_name; }

    // Reads n bytes (known to be there) into dst; hashed unless hash is false.
    void read(void* dst, size_t n, bool hash = true) {
        auto* p = static_cast<uint8_t*>(dst);
        for (size_t done = 0; done < n;) {
            const size_t len = std::min(k_chunk, n - done);
            if (std::fread(p + done, 1, len, m_file) != len)
                throw Error(
                    m_name + ": cannot read (" +
                    (std::ferror(m_file) ? errno_text(errno) : std::string("the file shrank while reading")) +
                    ")");
            if (hash) m_hash.update(p + done, len);
            done += len;
        }
        m_pos += n;
    }
    template <typename T>
    T get() {
        T v;
        read(&v, sizeof(T));
        return v;
    }
    void skip(uint64_t n) {
        std::vector<uint8_t> buf(std::min<uint64_t>(n, k_chunk));
        while (n > 0) {
            const size_t len = size_t(std::min<uint64_t>(n, buf.size()));
            read(buf.data(), len);
            n -= len;
        }
    }
    void hash_bytes(const void* data, size_t n) { m_hash.update(data, n); }
    uint64_t hash() const { return m_hash.finish(); }

    Error error(const std::string& what) const { return Error(m_name + ": " + what); }

  private:
    std::string m_name;
    std::FILE* m_file = nullptr;
    uint64_t m_size = 0, m_pos = 0;
    Hasher m_hash;
};

// What the sections held, checked against each other once the checksum has vouched for the bytes.
struct RawModel {
    std::optional<std::string> conf;
    bool has_scen = false;
    float aabb_scale = 0;
    double world_to_model[16] = {};
    std::optional<std::vector<float>> params;
    uint64_t params_count = 0;
    std::optional<std::vector<float>> density;
    uint32_t cascades = 0, resolution = 0;
    std::optional<TrainingState> training;
    uint64_t training_step = 0, training_count = 0;
    std::optional<std::vector<uint8_t>> relight;  // RLIT's payload, decoded once the checksum has vouched for it
    std::optional<std::vector<float>> view_directions;  // 3 per direction
    uint64_t view_count = 0;
    std::optional<std::string> object;  // OBJF's JSON text
    std::optional<ExposureState> exposure;  // EXPO: the training's per-image gains
};

void check_finite(const std::vector<float>& x, const Reader& in, const char* what) {
    if (const size_t i = first_non_finite(x); i < x.size())
        throw in.error(std::string(what) + " " + std::to_string(i) + " is NaN or Inf");
}

std::string tag_text(const char* tag) {
    std::string s;
    for (int i = 0; i < 4; ++i) {
        const unsigned char c = static_cast<unsigned char>(tag[i]);
        s += (c >= 32 && c < 127) ? char(c) : '?';
    }
    return s;
}

// Reads sections up to and including CKSM; throws on truncation, structural damage or a checksum mismatch.
RawModel read_sections(Reader& in) {
    RawModel raw;
    const auto truncated = [&](const std::string& where) {
        return in.error("truncated (" + where + "; the file has " + std::to_string(in.size()) + " bytes)");
    };
    char magic[8] = {};
    const size_t head = size_t(std::min<uint64_t>(in.size(), 8));
    in.read(magic, head);
    if (std::memcmp(magic, k_magic, head) != 0) throw in.error("not a nerfpt model file (wrong magic bytes)");
    if (head < 8 || in.remaining() < 4) throw truncated("inside the header");
    const auto version = in.get<uint32_t>();
    if (version != k_version)
        throw in.error("unsupported model file version " + std::to_string(version) +
                       " (this build reads version " + std::to_string(k_version) + ")");

    std::vector<std::string> seen;
    for (;;) {
        if (in.remaining() == 0) throw truncated("it ends before the checksum section");
        if (in.remaining() < k_section_header) throw truncated("inside a section header");
        char header[k_section_header];
        in.read(header, k_section_header, /*hash=*/false);
        const std::string tag(header, 4);
        uint64_t length;
        std::memcpy(&length, header + 4, 8);
        const std::string name = "section '" + tag_text(header) + "'";
        if (length > in.remaining())
            throw truncated(name + " needs " + std::to_string(length) + " bytes, " +
                            std::to_string(in.remaining()) + " are left");
        if (tag == "CKSM") {
            if (length != 8)
                throw in.error("corrupt checksum section (" + std::to_string(length) + " bytes)");
            const uint64_t expected = in.hash();
            uint64_t stored;
            in.read(&stored, 8, /*hash=*/false);
            if (in.remaining() != 0)
                throw in.error(std::to_string(in.remaining()) +
                               " unexpected bytes after the checksum section");
            if (stored != expected) throw in.error("checksum mismatch: the file is corrupt");
            return raw;
        }
        in.hash_bytes(header, k_section_header);
        for (const auto& s : seen)
            if (s == tag) throw in.error("duplicate " + name);
        seen.push_back(tag);
        const auto corrupt = [&] {
            return in.error("corrupt " + name + " (" + std::to_string(length) + " bytes)");
        };
        // Array lengths come from the section length, which is known to fit in the file; the counts stored
        // inside are compared with them after the checksum.
        if (tag == "CONF") {
            std::string text(size_t(length), '\0');
            in.read(text.data(), text.size());
            raw.conf = std::move(text);
        } else if (tag == "SCEN") {
            if (length != k_scen_bytes) throw corrupt();
            raw.aabb_scale = in.get<float>();
            in.read(raw.world_to_model, sizeof(raw.world_to_model));
            raw.has_scen = true;
        } else if (tag == "PARM") {
            if (length < 8 || (length - 8) % 4 != 0) throw corrupt();
            raw.params_count = in.get<uint64_t>();
            raw.params.emplace(size_t((length - 8) / 4));
            in.read(raw.params->data(), raw.params->size() * 4);
        } else if (tag == "OCCG") {
            if (length < 8 || (length - 8) % 4 != 0) throw corrupt();
            raw.cascades = in.get<uint32_t>();
            raw.resolution = in.get<uint32_t>();
            raw.density.emplace(size_t((length - 8) / 4));
            in.read(raw.density->data(), raw.density->size() * 4);
        } else if (tag == "VIEW") {
            if (length < 8 || (length - 8) % 12 != 0) throw corrupt();
            raw.view_count = in.get<uint64_t>();
            raw.view_directions.emplace(size_t((length - 8) / 4));
            in.read(raw.view_directions->data(), raw.view_directions->size() * 4);
        } else if (tag == "TRAN") {
            if (length < 32 || (length - 32) % 16 != 0) throw corrupt();
            TrainingState& t = raw.training.emplace();
            raw.training_step = in.get<uint64_t>();
            t.elapsed_seconds = in.get<double>();
            t.rays_per_step = in.get<uint32_t>();
            (void)in.get<uint32_t>();  // reserved
            raw.training_count = in.get<uint64_t>();
            const size_t n = size_t((length - 32) / 16);
            for (std::vector<float>* v : {&t.params, &t.adam.m, &t.adam.v, &t.adam.ema}) {
                v->resize(n);
                in.read(v->data(), n * 4);
            }
            t.adam.step = raw.training_step;
        } else if (tag == "EXPO") {
            if (length < 16 || (length - 16) % 36 != 0) throw corrupt();
            const uint64_t images = in.get<uint64_t>();
            ExposureState& e = raw.exposure.emplace();
            e.step = in.get<uint64_t>();
            if (images != (length - 16) / 36) throw in.error("corrupt section 'EXPO' (count does not match length)");
            for (std::vector<Rgb>* v : {&e.log_gain, &e.m, &e.v}) {
                v->resize(size_t(images));
                in.read(v->data(), v->size() * sizeof(Rgb));
            }
        } else if (tag == "OBJF") {
            std::string text(size_t(length), '\0');
            in.read(text.data(), text.size());
            raw.object = std::move(text);
        } else if (tag == "RLIT") {
            raw.relight.emplace(size_t(length));
            in.read(raw.relight->data(), raw.relight->size());
        } else {
            in.skip(length);  // a section from a newer writer that this version does not need
        }
    }
}

}  // namespace

uint64_t model_file_hash(const void* data, size_t size) {
    Hasher h;
    h.update(data, size);
    return h.finish();
}

void save_model(const fs::path& path, const NerfModel& model, bool with_training) {
    const std::string name = path.string();
    const auto refuse = [&](const std::string& why) { return Error(name + ": model not saved: " + why); };
    // Checked here as well as on loading, so that a broken model never replaces a good checkpoint.
    const size_t total = model.layout().total;
    if (model.params.size() != total)
        throw refuse("it has " + std::to_string(model.params.size()) + " parameters, its config needs " +
                     std::to_string(total));
    if (!std::isfinite(model.aabb_scale) || model.aabb_scale <= 0)
        throw refuse("aabb_scale " + std::to_string(model.aabb_scale) + " is not a positive number");
    if (!model.world_to_model.is_finite()) throw refuse("world_to_model has NaN or Inf");
    if (model.occupancy.cascades() != cascades_for_aabb_scale(model.aabb_scale) ||
        model.occupancy.resolution() != model.config.occupancy.resolution)
        throw refuse("the occupancy grid (" + std::to_string(model.occupancy.cascades()) + " cascades of " +
                     std::to_string(model.occupancy.resolution()) + "^3) does not match the config (" +
                     std::to_string(cascades_for_aabb_scale(model.aabb_scale)) + " of " +
                     std::to_string(model.config.occupancy.resolution) + "^3)");
    const auto check = [&](const std::vector<float>& x, const char* what) {
        if (x.size() != total)
            throw refuse(std::string(what) + " has " + std::to_string(x.size()) + " values, expected " +
                         std::to_string(total));
        if (const size_t i = first_non_finite(x); i < x.size())
            throw refuse(std::string(what) + " " + std::to_string(i) + " is NaN or Inf");
    };
    check(model.params, "parameter");
    if (const size_t i = first_non_finite(model.occupancy.density()); i < model.occupancy.density().size())
        throw refuse("occupancy density " + std::to_string(i) + " is NaN or Inf");
    for (size_t i = 0; i < model.view_directions.size(); ++i)
        if (const float len = length(model.view_directions[i]); !(len > 0.5f && len < 2.0f))
            throw refuse("view direction " + std::to_string(i) + " is not a unit vector");
    const TrainingState* training = with_training && model.training ? &*model.training : nullptr;
    if (training) {
        check(training->params, "training parameter");
        check(training->adam.m, "optimizer state m");
        check(training->adam.v, "optimizer state v");
        check(training->adam.ema, "optimizer state ema");
        if (!std::isfinite(training->elapsed_seconds)) throw refuse("elapsed_seconds is not finite");
        for (const auto* v : {&training->exposure.log_gain, &training->exposure.m, &training->exposure.v})
            for (const Rgb& x : *v)
                if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z))
                    throw refuse("an image's exposure state is NaN or Inf");
    }

    std::vector<uint8_t> relight;
    if (model.relight) {
        try {
            relight = encode_relight_section(*model.relight, model.aabb_scale);
        } catch (const Error& e) {
            throw refuse(e.what());
        }
    }

    std::string object;
    if (model.object) {
        object = object_frame_to_json(*model.object).dump();
        try {  // what the reader will check
            (void)object_frame_from_json(json::parse(object), "object frame");
        } catch (const Error& e) {
            throw refuse(e.what());
        }
    }

    const std::string conf = config_to_json(model.config).dump(2);
    AtomicWriter out(path);
    out.write(k_magic, 8);
    out.put(k_version);
    out.section("CONF", conf.size());
    out.write(conf.data(), conf.size());
    out.section("SCEN", k_scen_bytes);
    out.put(model.aabb_scale);
    for (const auto& row : model.world_to_model.m) out.write(row.data(), sizeof(double) * 4);
    out.section("PARM", 8 + 4 * uint64_t(total));
    out.put(uint64_t(total));
    out.write(model.params.data(), 4 * total);
    const std::vector<float>& density = model.occupancy.density();
    out.section("OCCG", 8 + 4 * uint64_t(density.size()));
    out.put(uint32_t(model.occupancy.cascades()));
    out.put(uint32_t(model.occupancy.resolution()));
    out.write(density.data(), 4 * density.size());
    if (!model.view_directions.empty()) {
        out.section("VIEW", 8 + 12 * uint64_t(model.view_directions.size()));
        out.put(uint64_t(model.view_directions.size()));
        for (const Vec3& d : model.view_directions) {
            const float xyz[3] = {d.x, d.y, d.z};
            out.write(xyz, sizeof(xyz));
        }
    }
    if (training) {
        out.section("TRAN", 32 + 16 * uint64_t(total));
        out.put(uint64_t(training->adam.step));
        out.put(training->elapsed_seconds);
        out.put(uint32_t(training->rays_per_step));
        out.put(uint32_t(0));  // reserved
        out.put(uint64_t(total));
        for (const auto* v : {&training->params, &training->adam.m, &training->adam.v, &training->adam.ema})
            out.write(v->data(), 4 * total);
        const ExposureState& e = training->exposure;
        if (!e.empty()) {
            out.section("EXPO", 16 + 36 * uint64_t(e.log_gain.size()));
            out.put(uint64_t(e.log_gain.size()));
            out.put(uint64_t(e.step));
            for (const auto* v : {&e.log_gain, &e.m, &e.v}) out.write(v->data(), v->size() * sizeof(Rgb));
        }
    }
    if (model.object) {
        out.section("OBJF", object.size());
        out.write(object.data(), object.size());
    }
    if (model.relight) {
        out.section("RLIT", relight.size());
        out.write(relight.data(), relight.size());
    }
    out.commit(out.hash());
}

NerfModel load_model(const fs::path& path) {
    Reader in(path);
    RawModel raw = read_sections(in);
    for (const auto& [present, tag] :
         {std::pair{raw.conf.has_value(), "CONF"}, std::pair{raw.has_scen, "SCEN"},
          std::pair{raw.params.has_value(), "PARM"}, std::pair{raw.density.has_value(), "OCCG"}})
        if (!present) throw in.error(std::string("missing section '") + tag + "'");

    NerfModel model;
    const json j = parse_json_text(*raw.conf, in.name() + ": stored config");
    model.config = config_from_json(j, in.name() + ": stored config");

    model.aabb_scale = raw.aabb_scale;
    if (!std::isfinite(raw.aabb_scale) || raw.aabb_scale <= 0)
        throw in.error("aabb_scale " + std::to_string(raw.aabb_scale) + " is not a positive number");
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) model.world_to_model.m[r][c] = raw.world_to_model[4 * r + c];
    if (!model.world_to_model.is_finite()) throw in.error("world_to_model has NaN or Inf");

    const size_t total = model.layout().total;
    if (raw.params_count != raw.params->size())
        throw in.error("corrupt section 'PARM' (count does not match length)");
    if (raw.params->size() != total)
        throw in.error("it has " + std::to_string(raw.params->size()) + " parameters, but its config needs " +
                       std::to_string(total));
    check_finite(*raw.params, in, "parameter");
    model.params = std::move(*raw.params);

    const int cascades = cascades_for_aabb_scale(model.aabb_scale);
    const int res = model.config.occupancy.resolution;
    if (raw.cascades != uint32_t(cascades) || raw.resolution != uint32_t(res))
        throw in.error("the occupancy grid has " + std::to_string(raw.cascades) + " cascades of " +
                       std::to_string(raw.resolution) + "^3 cells, the config needs " +
                       std::to_string(cascades) + " of " + std::to_string(res) + "^3");
    if (raw.density->size() != size_t(cascades) * size_t(res) * size_t(res) * size_t(res))
        throw in.error("corrupt section 'OCCG' (cell count does not match length)");
    check_finite(*raw.density, in, "occupancy density");
    model.occupancy = OccupancyGrid(cascades, res);
    try {
        model.occupancy.set_density(std::move(*raw.density), model.config.occupancy.threshold);
    } catch (const Error& e) {
        throw in.error(e.what());
    }

    if (raw.view_directions) {
        const std::vector<float>& v = *raw.view_directions;
        if (raw.view_count * 3 != v.size()) throw in.error("corrupt section 'VIEW' (count does not match length)");
        check_finite(v, in, "view direction component");
        for (size_t i = 0; i < v.size(); i += 3) {
            const Vec3 d(v[i], v[i + 1], v[i + 2]);
            const float len = length(d);
            if (!(len > 0.5f && len < 2.0f))
                throw in.error("view direction " + std::to_string(i / 3) + " is not a unit vector");
            model.view_directions.push_back(d / len);
        }
    }

    if (raw.training) {
        TrainingState& t = *raw.training;
        if (raw.training_count != t.params.size())
            throw in.error("corrupt section 'TRAN' (count does not match length)");
        if (t.params.size() != total)
            throw in.error("its training state has " + std::to_string(t.params.size()) +
                           " parameters, but its config needs " + std::to_string(total));
        if (!std::isfinite(t.elapsed_seconds)) throw in.error("training elapsed_seconds is not finite");
        check_finite(t.params, in, "training parameter");
        check_finite(t.adam.m, in, "optimizer state m");
        check_finite(t.adam.v, in, "optimizer state v");
        check_finite(t.adam.ema, in, "optimizer state ema");
        if (raw.exposure) {
            for (const auto* v : {&raw.exposure->log_gain, &raw.exposure->m, &raw.exposure->v})
                for (const Rgb& x : *v)
                    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z))
                        throw in.error("an image's exposure state in section 'EXPO' is NaN or Inf");
            t.exposure = std::move(*raw.exposure);
        }
        model.training = std::move(t);
    }
    if (raw.object)
        model.object = object_frame_from_json(parse_json_text(*raw.object, in.name() + ": section 'OBJF'"),
                                              in.name() + ": section 'OBJF'");
    if (raw.relight)
        model.relight = decode_relight_section(raw.relight->data(), raw.relight->size(), in.name(), model.aabb_scale);
    return model;
}

}  // namespace npt::nerf
