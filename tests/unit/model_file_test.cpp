// The .npt model file: bit-exact round trips with and without training state, and every way a file can be
// bad (truncated anywhere, a flipped byte, wrong magic, a future version, NaN under a valid checksum, sizes
// that contradict the stored config, missing sections), plus the atomic write: a failed save, at open time
// or halfway through the data, leaves the previous file byte for byte as it was.
#include "nerf/model_file.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstring>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "test_support.h"

namespace npt::nerf {
namespace {

namespace fs = std::filesystem;

constexpr size_t k_checksum_section = 4 + 8 + 8;  // the file's last section: tag, length, value

// Small enough for fast tests, with every part present: 2 cascades (aabb_scale 2) of 16^3 cells.
NerfModel test_model(bool with_training) {
    NerfModel m;
    m.config.encoding.grid.levels = 2;
    m.config.encoding.grid.log2_table_size = 10;
    m.config.occupancy.resolution = 16;
    m.aabb_scale = 2.0f;
    m.world_to_model = Mat4::translation(0.5, 0.25, -0.125) * Mat4::scale(0.33, 0.33, 0.33);
    m.world_to_model.m[3][0] = 1e-300;  // odd doubles must survive bit for bit
    const size_t total = m.layout().total;
    m.params.resize(total);
    for (size_t i = 0; i < total; ++i) m.params[i] = std::sin(float(i) * 0.37f) * 0.1f;
    m.params[1] = -0.0f;
    m.params[2] = std::numeric_limits<float>::denorm_min();
    m.occupancy = OccupancyGrid(cascades_for_aabb_scale(m.aabb_scale), 16);
    std::vector<float> density(m.occupancy.cell_count());
    for (size_t i = 0; i < density.size(); ++i) density[i] = float(i % 97) * 0.003f;
    m.occupancy.set_density(density, m.config.occupancy.threshold);
    if (with_training) {
        TrainingState t;
        t.params = m.params;
        for (float& p : t.params) p *= 1.5f;
        t.adam.m.assign(total, 0.25f);
        t.adam.v.assign(total, 1e-9f);
        t.adam.ema.assign(total, -3.0f);
        t.adam.m[5] = -7.0f;
        t.adam.step = 1234;
        t.elapsed_seconds = 56.789;
        m.training = std::move(t);
    }
    return m;
}

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

void expect_same_model(const NerfModel& a, const NerfModel& b, bool training) {
    EXPECT_EQ(config_to_json(a.config), config_to_json(b.config));
    EXPECT_EQ(a.aabb_scale, b.aabb_scale);
    EXPECT_EQ(std::memcmp(&a.world_to_model.m, &b.world_to_model.m, sizeof(a.world_to_model.m)), 0);
    EXPECT_TRUE(same_bits(a.params, b.params));
    EXPECT_EQ(a.occupancy.cascades(), b.occupancy.cascades());
    EXPECT_EQ(a.occupancy.resolution(), b.occupancy.resolution());
    EXPECT_TRUE(same_bits(a.occupancy.density(), b.occupancy.density()));
    EXPECT_EQ(a.occupancy.mean_density(), b.occupancy.mean_density());
    ASSERT_EQ(b.training.has_value(), training);
    if (!training) return;
    const TrainingState &ta = *a.training, &tb = *b.training;
    EXPECT_TRUE(same_bits(ta.params, tb.params));
    EXPECT_TRUE(same_bits(ta.adam.m, tb.adam.m));
    EXPECT_TRUE(same_bits(ta.adam.v, tb.adam.v));
    EXPECT_TRUE(same_bits(ta.adam.ema, tb.adam.ema));
    EXPECT_EQ(ta.adam.step, tb.adam.step);
    EXPECT_EQ(ta.elapsed_seconds, tb.elapsed_seconds);
}

std::string read_bytes(const fs::path& path) {
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

// Recomputes the checksum of a file edited on purpose, so that the loader gets past it.
void fix_checksum(std::string& bytes) {
    const size_t covered = bytes.size() - k_checksum_section;
    ASSERT_EQ(bytes.substr(covered, 4), "CKSM");
    const uint64_t h = model_file_hash(bytes.data(), covered);
    std::memcpy(bytes.data() + bytes.size() - 8, &h, 8);
}

// Offset of a section's payload (after its tag and length).
size_t payload_of(const std::string& bytes, const char* tag) {
    const size_t at = bytes.find(tag);
    EXPECT_NE(at, std::string::npos) << tag;
    return at + 12;
}

TEST(ModelFile, RoundTripWithTraining) {
    const fs::path path = test::temp_dir() / "model.npt";
    const NerfModel m = test_model(true);
    save_model(path, m);
    expect_same_model(m, load_model(path), true);
    // Saving again over the file gives the same bytes.
    const std::string first = read_bytes(path);
    save_model(path, load_model(path));
    EXPECT_EQ(read_bytes(path), first);
}

TEST(ModelFile, RoundTripWithoutTraining) {
    const fs::path dir = test::temp_dir();
    const NerfModel m = test_model(true);
    save_model(dir / "a.npt", m, /*with_training=*/false);
    expect_same_model(m, load_model(dir / "a.npt"), false);
    save_model(dir / "b.npt", test_model(false));
    expect_same_model(test_model(false), load_model(dir / "b.npt"), false);
    EXPECT_EQ(read_bytes(dir / "a.npt"), read_bytes(dir / "b.npt"));
    EXPECT_EQ(read_bytes(dir / "a.npt").find("TRAN"), std::string::npos);
}

TEST(ModelFile, LayoutOfTheBytes) {
    // The documented header and section order (docs/formats.md), so that other tools can read the file.
    const fs::path path = test::temp_dir() / "model.npt";
    const NerfModel m = test_model(false);
    save_model(path, m);
    const std::string b = read_bytes(path);
    EXPECT_EQ(b.substr(0, 8), "NPTNERF1");
    uint32_t version;
    std::memcpy(&version, b.data() + 8, 4);
    EXPECT_EQ(version, 1u);
    EXPECT_EQ(b.substr(12, 4), "CONF");
    uint64_t conf_len;
    std::memcpy(&conf_len, b.data() + 16, 8);
    EXPECT_EQ(nlohmann::json::parse(b.substr(24, conf_len)), config_to_json(m.config));
    EXPECT_EQ(b.substr(24 + conf_len, 4), "SCEN");
    const size_t parm = payload_of(b, "PARM");
    uint64_t count;
    std::memcpy(&count, b.data() + parm, 8);
    EXPECT_EQ(count, m.params.size());
    float p7;
    std::memcpy(&p7, b.data() + parm + 8 + 7 * 4, 4);
    EXPECT_EQ(p7, m.params[7]);
    const size_t occg = payload_of(b, "OCCG");
    uint32_t cascades, resolution;
    std::memcpy(&cascades, b.data() + occg, 4);
    std::memcpy(&resolution, b.data() + occg + 4, 4);
    EXPECT_EQ(cascades, 2u);
    EXPECT_EQ(resolution, 16u);
    uint64_t stored;
    std::memcpy(&stored, b.data() + b.size() - 8, 8);
    EXPECT_EQ(stored, model_file_hash(b.data(), b.size() - k_checksum_section));
}

TEST(ModelFile, HashSeesLengthAndEveryByte) {
    const char zeros[16] = {};
    EXPECT_NE(model_file_hash(zeros, 0), model_file_hash(zeros, 1));
    EXPECT_NE(model_file_hash(zeros, 1), model_file_hash(zeros, 2));
    EXPECT_NE(model_file_hash(zeros, 8), model_file_hash(zeros, 16));
    char one[16] = {};
    one[13] = 1;
    EXPECT_NE(model_file_hash(zeros, 16), model_file_hash(one, 16));
}

TEST(ModelFile, Truncated) {
    const fs::path dir = test::temp_dir();
    save_model(dir / "model.npt", test_model(true));
    const std::string full = read_bytes(dir / "model.npt");
    const size_t parm = payload_of(full, "PARM");
    for (size_t size : {size_t(0), size_t(5), size_t(8), size_t(10), size_t(12), size_t(15), parm - 3,
                        parm + 101, full.size() - k_checksum_section, full.size() - 9, full.size() - 1}) {
        SCOPED_TRACE(size);
        const fs::path path = dir / "cut.npt";
        test::write_file(path, full.substr(0, size));
        test::expect_error_message([&] { load_model(path); }, {path.string(), "truncated"});
    }
}

TEST(ModelFile, FlippedByteFailsTheChecksum) {
    const fs::path dir = test::temp_dir();
    save_model(dir / "model.npt", test_model(true));
    const std::string full = read_bytes(dir / "model.npt");
    for (size_t at : {payload_of(full, "PARM") + 8 + 401, payload_of(full, "CONF") + 20,
                      payload_of(full, "TRAN") + 3, full.size() - k_checksum_section - 1}) {
        SCOPED_TRACE(at);
        std::string b = full;
        b[at] = char(b[at] ^ 0x10);
        test::write_file(dir / "bad.npt", b);
        test::expect_error_message([&] { load_model(dir / "bad.npt"); }, {"bad.npt", "checksum mismatch"});
    }
}

TEST(ModelFile, WrongMagic) {
    const fs::path dir = test::temp_dir();
    save_model(dir / "model.npt", test_model(false));
    std::string b = read_bytes(dir / "model.npt");
    b[3] = 'X';
    test::write_file(dir / "bad.npt", b);
    test::expect_error_message([&] { load_model(dir / "bad.npt"); }, {"bad.npt", "not a nerfpt model file"});
    test::write_file(dir / "text.npt", "{\"encoding\": {}}");
    test::expect_error_message([&] { load_model(dir / "text.npt"); },
                               {"text.npt", "not a nerfpt model file"});
    test::write_file(dir / "short.npt", "NPX");
    test::expect_error_message([&] { load_model(dir / "short.npt"); },
                               {"short.npt", "not a nerfpt model file"});
}

TEST(ModelFile, FutureVersion) {
    const fs::path dir = test::temp_dir();
    save_model(dir / "model.npt", test_model(false));
    std::string b = read_bytes(dir / "model.npt");
    const uint32_t v2 = 2;
    std::memcpy(b.data() + 8, &v2, 4);
    fix_checksum(b);
    test::write_file(dir / "v2.npt", b);
    test::expect_error_message([&] { load_model(dir / "v2.npt"); }, {"v2.npt", "unsupported", "version 2"});
}

TEST(ModelFile, NanUnderAValidChecksum) {
    const fs::path dir = test::temp_dir();
    save_model(dir / "model.npt", test_model(true));
    const std::string full = read_bytes(dir / "model.npt");
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    struct Case {
        size_t offset;
        float value;
        std::string message;
    };
    const size_t n = test_model(false).params.size();
    for (const Case& c :
         {Case{payload_of(full, "PARM") + 8 + 7 * 4, nan, "parameter 7 is NaN or Inf"},
          Case{payload_of(full, "OCCG") + 8 + 11 * 4, inf, "occupancy density 11 is NaN or Inf"},
          Case{payload_of(full, "TRAN") + 32 + (2 * n + 3) * 4, nan, "state v 3 is NaN or Inf"}}) {
        SCOPED_TRACE(c.message);
        std::string b = full;
        std::memcpy(b.data() + c.offset, &c.value, 4);
        fix_checksum(b);
        test::write_file(dir / "nan.npt", b);
        test::expect_error_message([&] { load_model(dir / "nan.npt"); }, {"nan.npt", c.message});
    }
}

TEST(ModelFile, SaveRefusesNonFiniteModels) {
    const fs::path path = test::temp_dir() / "model.npt";
    NerfModel m = test_model(true);
    m.params[3] = std::numeric_limits<float>::quiet_NaN();
    test::expect_error_message([&] { save_model(path, m); }, {path.string(), "not saved", "parameter 3"});
    m = test_model(true);
    m.training->adam.m[9] = -std::numeric_limits<float>::infinity();
    test::expect_error_message([&] { save_model(path, m); }, {path.string(), "not saved", "state m 9"});
    EXPECT_FALSE(fs::exists(path));
    m = test_model(true);
    m.params.pop_back();
    test::expect_error_message([&] { save_model(path, m); }, {path.string(), "not saved", "parameters"});
}

TEST(ModelFile, SizesMustMatchTheStoredConfig) {
    const fs::path dir = test::temp_dir();
    save_model(dir / "model.npt", test_model(false));
    const std::string full = read_bytes(dir / "model.npt");
    // "levels": 2 -> 3 in the stored config: the parameter count no longer fits it.
    std::string b = full;
    const size_t at = b.find("\"levels\": 2");
    ASSERT_NE(at, std::string::npos);
    b[at + 10] = '3';
    fix_checksum(b);
    test::write_file(dir / "bad.npt", b);
    test::expect_error_message([&] { load_model(dir / "bad.npt"); },
                               {"bad.npt", "parameters", "config needs"});
    // The grid resolution in the config no longer fits the stored grid.
    b = full;
    const size_t res = b.find("\"resolution\": 16");
    ASSERT_NE(res, std::string::npos);
    b[res + 15] = '8';
    fix_checksum(b);
    test::write_file(dir / "bad.npt", b);
    test::expect_error_message([&] { load_model(dir / "bad.npt"); }, {"bad.npt", "occupancy grid"});
    // A stored config that is itself invalid names the field.
    b = full;
    b[at + 10] = '0';
    fix_checksum(b);
    test::write_file(dir / "bad.npt", b);
    test::expect_error_message([&] { load_model(dir / "bad.npt"); }, {"bad.npt", "'encoding.levels'"});
}

TEST(ModelFile, UnknownSectionsAreSkippedAndRequiredOnesMustBeThere) {
    const fs::path dir = test::temp_dir();
    const NerfModel m = test_model(true);
    save_model(dir / "model.npt", m);
    const std::string full = read_bytes(dir / "model.npt");
    // A section from a newer writer, before the checksum.
    std::string b = full.substr(0, full.size() - k_checksum_section);
    const uint64_t len = 5;
    b += "XTRA" + std::string(reinterpret_cast<const char*>(&len), 8) + "hello";
    b += full.substr(full.size() - k_checksum_section);
    fix_checksum(b);
    test::write_file(dir / "newer.npt", b);
    expect_same_model(m, load_model(dir / "newer.npt"), true);
    // A required section renamed away.
    b = full;
    b[b.find("OCCG") + 3] = 'X';
    fix_checksum(b);
    test::write_file(dir / "missing.npt", b);
    test::expect_error_message([&] { load_model(dir / "missing.npt"); },
                               {"missing.npt", "missing section 'OCCG'"});
    // Bytes after the checksum.
    test::write_file(dir / "trailing.npt", full + "x");
    test::expect_error_message([&] { load_model(dir / "trailing.npt"); },
                               {"trailing.npt", "after the checksum"});
}

TEST(ModelFile, MissingFile) {
    const fs::path path = test::temp_dir() / "nope.npt";
    test::expect_error_message([&] { load_model(path); }, {path.string(), "not found"});
}

TEST(ModelFile, UnwritableFolder) {
    const fs::path dir = test::temp_dir();
    const fs::path path = dir / "no_such_folder" / "model.npt";
    test::expect_error_message([&] { save_model(path, test_model(false)); },
                               {path.string(), "cannot create"});
    // A read-only folder; root writes there anyway, so this part only runs for other users.
    if (::geteuid() != 0) {
        fs::create_directories(dir / "ro");
        fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
        const fs::path ro = dir / "ro" / "model.npt";
        test::expect_error_message([&] { save_model(ro, test_model(false)); },
                                   {ro.string(), "cannot create"});
        fs::permissions(dir / "ro", fs::perms::owner_all);
    }
}

std::vector<std::string> folder_entries(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

TEST(ModelFile, FailedSaveLeavesThePreviousFile) {
    const fs::path dir = test::temp_dir();
    const fs::path path = dir / "model.npt";
    save_model(path, test_model(false));
    const std::string before = read_bytes(path);
    NerfModel other = test_model(true);
    other.params[0] = 0.75f;

    // Failing at the start: the temporary file's name is taken by a folder.
    const fs::path blocker = path.string() + ".tmp-" + std::to_string(::getpid());
    fs::create_directories(blocker);
    test::expect_error_message([&] { save_model(path, other); }, {path.string(), "cannot create"});
    fs::remove(blocker);
    EXPECT_EQ(read_bytes(path), before);

    // Failing halfway through the data: a file size limit makes writes past 20000 bytes fail (EFBIG), as a
    // full disk would; SIGXFSZ is ignored so that the write reports it instead of killing the process.
    const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
    rlimit old_limit{};
    ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old_limit), 0);
    rlimit small = old_limit;
    small.rlim_cur = 20000;
    ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
    try {
        save_model(path, other);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    }
    ::setrlimit(RLIMIT_FSIZE, &old_limit);
    std::signal(SIGXFSZ, old_handler);
    EXPECT_EQ(read_bytes(path), before);
    EXPECT_EQ(folder_entries(dir), std::vector<std::string>{"model.npt"});  // no temporary file left behind

    // And the same save works once the disk has room again.
    save_model(path, other);
    EXPECT_EQ(load_model(path).params[0], 0.75f);
    EXPECT_EQ(folder_entries(dir), std::vector<std::string>{"model.npt"});
}

}  // namespace
}  // namespace npt::nerf
