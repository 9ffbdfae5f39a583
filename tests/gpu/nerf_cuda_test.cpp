// The CUDA NeRF backend against the CPU reference: the field (fp32 path: same code; fp16 tensor-core path:
// within half-precision rounding), rendered pixels, training gradients of one batch, convergence, and models
// moving between the backends (resume, render). Registered only where a GPU exists (label gpu).
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <thread>
#include <vector>

#include "core/rng.h"
#include "bake/bake_grid.h"
#include "core/cuda/device_buffer.h"
#include "core/error.h"
#include "nerf/backend/nerf_backend.h"
#include "nerf/cuda/cuda_field.h"
#include "nerf/cuda/cuda_renderer.h"
#include "nerf/cuda/cuda_trainer.h"
#include "nerf/model_file.h"
#include "nerf/object_frame.h"
#include "nerf/orbit_camera.h"
#include "nerf/render_view.h"
#include "nerf/trainer.h"
#include "nerf_test_scene.h"
#include "test_support.h"

namespace npt::nerf {
namespace {

namespace fs = std::filesystem;

// The sphere scene's small config with the encoding the tensor-core kernels take (32 features: 8 levels x 4).
NerfConfig gpu_sphere_config() {
    NerfConfig c = test::small_sphere_config();
    c.encoding.grid.levels = 8;
    c.encoding.grid.features_per_level = 4;
    c.training.cuda_batch_samples = 1 << 14;
    return c;
}

// A model with weights far from their tiny initial values, so that every layer matters: hash entries uniform in
// [-1, 1], MLP weights from create_model (Xavier), and an occupancy grid with 30% empty cells (or none).
NerfModel random_model(uint64_t seed, bool empty_cells = true) {
    const Dataset d = test::make_sphere_scene({.views = 2, .size = 8, .view_seed = 1});
    NerfModel m = create_model(gpu_sphere_config(), d.aabb_scale, ngp_world_to_model(d.scale, d.offset));
    const NerfLayout l = m.layout();
    Pcg32 rng(seed, 7);
    for (size_t i = l.grid_offset; i < l.total; ++i) m.params[i] = 2.0f * rng.next_float() - 1.0f;
    std::vector<float> density(m.occupancy.cell_count());
    for (float& v : density) v = empty_cells && rng.next_float() < 0.3f ? 0.0f : 1.0f;
    m.occupancy.set_density(density, 0.01f);
    return m;
}

struct Points {
    std::vector<Vec3> pos, dir;
};
Points random_points(size_t n, uint64_t seed) {
    Pcg32 rng(seed, 3);
    Points p;
    for (size_t i = 0; i < n; ++i) {
        p.pos.push_back(Vec3(rng.next_float(), rng.next_float(), rng.next_float()));
        Vec3 d;
        do d = Vec3(2 * rng.next_float() - 1, 2 * rng.next_float() - 1, 2 * rng.next_float() - 1);
        while (length_squared(d) > 1.0f || length_squared(d) < 1e-4f);
        p.dir.push_back(normalize(d));
    }
    return p;
}

TEST(NerfCuda, Fp32FieldEqualsTheCpuField) {
    const NerfModel m = random_model(1);
    const Points pts = random_points(5000, 2);
    std::vector<float> sigma;
    std::vector<Rgb> rgb;
    cuda::evaluate_field(m, pts.pos, pts.dir, cuda::Precision::fp32, sigma, rgb);
    const NerfFieldView f = m.field();
    double max_rel = 0;
    for (size_t i = 0; i < pts.pos.size(); ++i) {
        float s;
        Rgb c;
        f.query(pts.pos[i], pts.dir[i], &s, &c);
        max_rel = std::max(max_rel, std::fabs(double(sigma[i]) - s) / std::max(1e-6, double(s)));
        // Colours lie in [0, 1]: absolute error (relative to full scale).
        for (int k = 0; k < 3; ++k) max_rel = std::max(max_rel, std::fabs(double(rgb[i][k]) - c[k]));
    }
    // The same float code on both sides; only contraction into FMAs differs: far below the issue's 1e-3.
    EXPECT_LT(max_rel, 1e-4);
}

TEST(NerfCuda, Fp16FieldIsTheCpuFieldWithinHalfPrecision) {
    const NerfModel m = random_model(3);
    const Points pts = random_points(20000, 4);
    std::vector<float> sigma;
    std::vector<Rgb> rgb;
    cuda::evaluate_field(m, pts.pos, pts.dir, cuda::Precision::fp16, sigma, rgb);
    const NerfFieldView f = m.field();
    double max_log_sigma = 0, max_rgb = 0, sum_log_sigma = 0;
    for (size_t i = 0; i < pts.pos.size(); ++i) {
        float s;
        Rgb c;
        f.query(pts.pos[i], pts.dir[i], &s, &c);
        const double d = std::fabs(std::log(double(sigma[i])) - std::log(double(s)));
        max_log_sigma = std::max(max_log_sigma, d);
        sum_log_sigma += d;
        for (int k = 0; k < 3; ++k) max_rgb = std::max(max_rgb, std::fabs(double(rgb[i][k]) - c[k]));
    }
    std::printf("fp16 field: max |d log sigma| %.2e (mean %.2e), max |d rgb| %.2e\n", max_log_sigma,
                sum_log_sigma / double(pts.pos.size()), max_rgb);
    // fp16 keeps 11 significant bits (unit roundoff u = 2^-11 = 4.9e-4). The inputs (features, weights) and the
    // output of each of the 5 layers are rounded once: about 7 roundings on the way to an output, each
    // amplified by at most the norm of the following layers (the Xavier weights here have norms ~1-2), so
    // |error| <~ 7 u * 4 = 1.4e-2 in log sigma (the raw output). Colour goes through a sigmoid (slope <= 1/4):
    // 3.5e-3. The limits are those bounds rounded up.
    EXPECT_LT(max_log_sigma, 2e-2);
    EXPECT_LT(max_rgb, 5e-3);
}

// Pixels of the fp32 GPU path against render_view. `strict`: a grid with every cell occupied, so that the
// ~1e-7 difference between the GPU's float camera-to-model matrix and the CPU's double transform cannot move
// a sample across a skipped cell's boundary; every pixel within 1e-3 (pixels are in [0, 1]: the issue's 1e-3
// relative at full scale). With empty cells, or an object box (`object_only`), a sample within that rounding of
// a cell's or the box's face can fall on either side: 99.5% of the values within 1e-3.
void expect_pixels_match(const NerfModel& m, bool strict, bool object_only = false) {
    const Dataset views = test::make_sphere_scene({.views = 3, .size = 40, .view_seed = 9});
    cuda::CudaViewRenderer r32(m, cuda::Precision::fp32), r16(m, cuda::Precision::fp16);
    for (size_t v = 0; v < views.cameras.size(); ++v) {
        ViewOptions o;
        o.background = Rgb(0.2f, 0.5f, 0.9f);
        o.object_only = object_only;
        const Image cpu = render_view(m, views.cameras[v], o);
        const Image g32 = r32.render(views.cameras[v], o);
        const Image g16 = r16.render(views.cameras[v], o);
        double max32 = 0, se16 = 0;
        size_t off = 0;
        for (size_t i = 0; i < cpu.pixels.size(); ++i) {
            const double d = std::fabs(g32.pixels[i] - cpu.pixels[i]);
            max32 = std::max(max32, d);
            off += d > 1e-3;
            se16 += std::pow(double(g16.pixels[i]) - cpu.pixels[i], 2);
        }
        const double psnr16 = -10.0 * std::log10(se16 / double(cpu.pixels.size()) + 1e-30);
        std::printf("view %zu (%s grid): fp32 max |diff| %.2e, %zu values over 1e-3; fp16 PSNR against the CPU "
                    "%.1f dB\n",
                    v, object_only ? "object, full" : strict ? "full" : "sparse", max32, off, psnr16);
        if (strict)
            EXPECT_LT(max32, 1e-3) << "view " << v;
        else
            EXPECT_LE(off, cpu.pixels.size() / 200) << "view " << v;
        // fp16 colours are within 5e-3 (Fp16FieldIs...): a PSNR above 40 dB against the fp32 image.
        EXPECT_GT(psnr16, 40.0) << "view " << v;
    }
}

TEST(NerfCuda, RenderedPixelsMatchTheCpu) {
    expect_pixels_match(random_model(5, false), true);
    expect_pixels_match(random_model(6, true), false);
}

// `view --object` / `eval --object` on the GPU: the march passes over the samples outside the object's box as the
// CPU drops them (object_cut.h), so the pixels are the CPU's within fp32 rounding, but for samples within rounding
// of the box's faces (on the H200: 1 value of 6 400 at 1.5e-3 in one view): the sparse grid's criterion. The box,
// half the model's cube wide and standing on its middle, cuts the model.
TEST(NerfCuda, TheObjectAloneMatchesTheCpu) {
    NerfModel m = random_model(5, false);
    const double world_per_model = 1.0 / model_scale(m);
    const Vec3 centre = model_centre_world(m);
    ObjectFrame f;  // object units = model units, +Z up = world +Z
    f.object_to_world = Mat4::translation(centre.x, centre.y, centre.z) *
                        Mat4::scale(world_per_model, world_per_model, world_per_model);
    f.box_min = Vec3(-0.25f, -0.25f, 0.0f);
    f.box_max = Vec3(0.25f, 0.25f, 0.5f);
    m.object = f;
    expect_pixels_match(m, false, true);
    // The cut is real: the CPU's object image has less coverage than the whole model's.
    const Dataset views = test::make_sphere_scene({.views = 1, .size = 40, .view_seed = 9});
    ViewOptions whole, alone;
    alone.object_only = true;
    const Image a = render_view(m, views.cameras[0], whole), b = render_view(m, views.cameras[0], alone);
    double cover_a = 0, cover_b = 0;
    for (size_t i = 3; i < a.pixels.size(); i += 4) {
        cover_a += a.pixels[i];
        cover_b += b.pixels[i];
    }
    EXPECT_LT(cover_b, 0.8 * cover_a);
    EXPECT_GT(cover_b, 0.0);
}

// The gradient of one batch (the same rays: both trainers draw them from (seed, step, ray)) on both backends,
// with the surface-smoothness loss at `smoothness` (0: off; its rays come in groups of three), and with
// `focus` most rays drawn in a rectangle of each image (train_pixel.h's subject rays).
void expect_gradient_matches_the_cpu(float smoothness, bool focus = false) {
    Dataset train = test::make_sphere_scene({.views = 10, .size = 32, .view_seed = 1});
    NerfConfig cfg = gpu_sphere_config();
    cfg.loss.surface_smoothness = smoothness;
    if (focus) {
        for (size_t i = 0; i < train.cameras.size(); ++i)
            train.subject_rects.push_back({4.0f + float(i), 6.0f, 20.0f + float(i), 26.5f});
        cfg.training.subject_rays = 0.8f;
    }
    cfg.training.batch_samples = 1 << 20;       // the CPU keeps every ray
    cfg.training.cuda_batch_samples = 1 << 17;  // and so does the GPU (its sample buffer holds 8x this)
    NerfModel base = create_model(cfg, train.aabb_scale, ngp_world_to_model(train.scale, train.offset));
    // A partly trained model gives gradients that are not dominated by the initial near-zero grid.
    {
        Trainer warm(base, train);
        for (int i = 0; i < 60; ++i) warm.step();
        warm.sync_model();
    }
    base.training->rays_per_step = 512;
    NerfModel a = base, b = base;
    std::vector<float> g_cpu, g_gpu;
    Trainer cpu(a, train);
    const StepStats sc = cpu.gradient(g_cpu);
    cuda::CudaTrainer gpu(b, train);
    const StepStats sg = gpu.gradient(g_gpu);
    const uint32_t rays = smoothness > 0.0f ? 510u : 512u;  // whole groups of three
    ASSERT_EQ(sc.rays, rays);
    ASSERT_EQ(sg.rays, rays) << "the GPU dropped rays";
    EXPECT_NEAR(sg.loss, sc.loss, 2e-2 * sc.loss + 1e-6);  // fp16 field: ~1e-3 in colours
    if (smoothness > 0.0f) {
        std::printf("surface-smoothness loss per group: CPU %.4e, GPU %.4e\n", sc.smoothness, sg.smoothness);
        EXPECT_GT(sc.smoothness, 0.0);
        // The surface points come from fp16 densities: a few 1e-3 of the loss, far from a missing group.
        EXPECT_NEAR(sg.smoothness, sc.smoothness, 5e-2 * sc.smoothness);
    }
    const NerfLayout l = a.layout();
    auto rel = [&](size_t begin, size_t end) {
        double num = 0, den = 0;
        for (size_t i = begin; i < end; ++i) {
            num += std::pow(double(g_gpu[i]) - g_cpu[i], 2);
            den += std::pow(double(g_cpu[i]), 2);
        }
        return std::sqrt(num / std::max(den, 1e-300));
    };
    const double density = rel(l.density_offset, l.color_offset), color = rel(l.color_offset, l.grid_offset),
                 grid = rel(l.grid_offset, l.total);
    std::printf("gradient relative error (2-norm): density MLP %.2e, colour MLP %.2e, hash grid %.2e\n", density,
                color, grid);
    // The GPU evaluates the network in fp16 (see Fp16FieldIsTheCpuFieldWithinHalfPrecision: ~1e-2 in the raw
    // outputs at worst, ~1e-3 typically) and backpropagates fp16 gradients (loss scale 128, 11-bit mantissas):
    // another ~7 roundings. In the 2-norm over a block the typical error counts: ~sqrt(14) u ~ 2e-3 per
    // sample, more where ReLU kinks flip. 3e-2 leaves that margin; a wrong index or a missing term gives O(1).
    EXPECT_LT(density, 3e-2);
    EXPECT_LT(color, 3e-2);
    EXPECT_LT(grid, 3e-2);
}

TEST(NerfCuda, GradientOfABatchMatchesTheCpuTrainer) { expect_gradient_matches_the_cpu(0.0f); }

TEST(NerfCuda, GradientWithSubjectRaysMatchesTheCpuTrainer) { expect_gradient_matches_the_cpu(0.0f, true); }

TEST(NerfCuda, GradientWithTheSurfaceSmoothnessLossMatchesTheCpuTrainer) {
    // A weight at which the smoothness term is a large part of the density's gradient.
    expect_gradient_matches_the_cpu(10.0f);
}

double held_out_psnr(ViewRendererBackend& r, const Dataset& test) {
    double sum = 0;
    for (size_t v = 0; v < test.cameras.size(); ++v) {
        const Image img = r.render(test.cameras[v], {});
        double se = 0;
        const uint8_t* gt = test.image(v);
        for (size_t p = 0; p < size_t(test.width) * test.height; ++p) {
            const float a = gt[4 * p + 3] / 255.0f;
            for (int k = 0; k < 3; ++k) se += std::pow(img.pixels[4 * p + k] - (gt[4 * p + k] / 255.0 * a + 1 - a), 2);
        }
        sum += psnr_from_mse(se / (3.0 * test.width * test.height));
    }
    return sum / double(test.cameras.size());
}

TEST(NerfCuda, TrainingConvergesAndTheModelRendersOnTheCpu) {
    const Dataset train = test::make_sphere_scene({.views = 20, .size = 32, .view_seed = 1});
    const Dataset test = test::make_sphere_scene({.views = 5, .size = 32, .view_seed = 2});
    NerfModel model = create_model(gpu_sphere_config(), train.aabb_scale, ngp_world_to_model(train.scale, train.offset));
    cuda::CudaTrainer trainer(model, train);
    double first = 0, last = 0;
    for (int i = 0; i < 1000; ++i) {
        const StepStats s = trainer.step();
        ASSERT_TRUE(std::isfinite(s.loss)) << "step " << i;
        if (i == 0) first = s.loss;
        last = s.loss;
    }
    trainer.sync_model();
    const auto gpu = make_view_renderer(Backend::cuda, model);
    const auto cpu = make_view_renderer(Backend::cpu, model);
    const double p_gpu = held_out_psnr(*gpu, test), p_cpu = held_out_psnr(*cpu, test);
    std::printf("1000 GPU steps: loss %.4f -> %.4f, held-out PSNR %.2f dB (GPU render), %.2f dB (CPU render), "
                "occupied %.1f%%\n",
                first, last, p_gpu, p_cpu, 100.0 * model.occupancy.occupied_fraction());
    // The CPU trainer reaches > 24 dB on this scene in 400 steps of 2^13 samples (NerfTraining tests).
    EXPECT_LT(last, 0.2 * first);
    EXPECT_GT(p_cpu, 24.0);
    EXPECT_NEAR(p_gpu, p_cpu, 0.1);  // fp16 inference within 0.1 dB of the fp32 CPU render
    EXPECT_LT(model.occupancy.occupied_fraction(), 0.5);

    // Saved and loaded, the GPU-trained model resumes on the CPU.
    const fs::path dir = test::temp_dir();
    save_model(dir / "gpu.npt", model, true);
    NerfModel loaded = load_model(dir / "gpu.npt");
    Trainer on_cpu(loaded, train);
    EXPECT_EQ(on_cpu.steps_done(), 1000u);
    const StepStats s = on_cpu.step();
    EXPECT_TRUE(std::isfinite(s.loss));
    EXPECT_LT(s.loss, 2.0 * last + 1e-3);
}

TEST(NerfCuda, CpuTrainedModelResumesOnTheGpu) {
    const Dataset train = test::make_sphere_scene({.views = 10, .size = 32, .view_seed = 1});
    NerfModel model = create_model(gpu_sphere_config(), train.aabb_scale, ngp_world_to_model(train.scale, train.offset));
    Trainer cpu(model, train);
    double last_cpu = 0;
    for (int i = 0; i < 100; ++i) last_cpu = cpu.step().loss;
    cpu.sync_model();
    const fs::path dir = test::temp_dir();
    save_model(dir / "cpu.npt", model, true);
    NerfModel loaded = load_model(dir / "cpu.npt");
    cuda::CudaTrainer gpu(loaded, train);
    EXPECT_EQ(gpu.steps_done(), 100u);
    double last = 0;
    for (int i = 0; i < 50; ++i) last = gpu.step().loss;
    EXPECT_EQ(gpu.steps_done(), 150u);
    EXPECT_TRUE(std::isfinite(last));
    EXPECT_LT(last, 1.5 * last_cpu + 1e-3) << "resuming must not start over";
}

TEST(NerfCuda, SigkilledGpuTrainingResumesFromItsCheckpoint) {
    const fs::path cli = test::cli_binary();
    if (!fs::exists(cli)) GTEST_SKIP() << "nerfpt binary not found: " << cli;
    const fs::path dir = test::temp_dir();
    test::write_dataset(test::make_sphere_scene({.views = 8, .size = 16, .view_seed = 4}), dir / "data", 40.0f);
    test::write_file(dir / "config.json",
                     R"({"encoding": {"levels": 8, "features_per_level": 4, "log2_table_size": 12,
                                      "finest_resolution": 64},
                         "occupancy": {"resolution": 16}, "training": {"cuda_batch_samples": 4096}})");
    const fs::path model = dir / "m.npt";
    const int pid = test::spawn_cli({"train", (dir / "data").string(), "-o", model.string(), "--config",
                                     (dir / "config.json").string(), "--backend", "cuda", "--steps", "1000000",
                                     "--checkpoint-every", "200", "-q"},
                                    dir / "killed.log");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (!fs::exists(model) && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    kill(pid, SIGKILL);
    ASSERT_EQ(test::wait_exit(pid), 128 + SIGKILL) << test::read_text(dir / "killed.log");
    const NerfModel partial = load_model(model);  // complete, never torn
    ASSERT_TRUE(partial.training);
    const uint64_t at = partial.training->adam.step;
    EXPECT_GE(at, 200u);
    EXPECT_EQ(at % 200, 0u);
    const uint64_t target = at + 300;
    ASSERT_EQ(test::run_cli({"train", (dir / "data").string(), "-o", model.string(), "--backend", "cuda",
                             "--steps", std::to_string(target), "--resume", "-q"},
                            dir / "resume.log"),
              0)
        << test::read_text(dir / "resume.log");
    const NerfModel resumed = load_model(model);
    EXPECT_EQ(resumed.training->adam.step, target);
    EXPECT_GT(resumed.training->elapsed_seconds, partial.training->elapsed_seconds);
}

}  // namespace
}  // namespace npt::nerf

namespace npt::nerf {
namespace {

// A bake on the GPU evaluates the same fp32 field as the CPU bake: the same voxels, the same values.
TEST(NerfCuda, GpuBakeEqualsTheCpuBake) {
    const Dataset train = test::make_sphere_scene({.views = 12, .size = 32, .view_seed = 1});
    NerfModel model = create_model(gpu_sphere_config(), train.aabb_scale, ngp_world_to_model(train.scale, train.offset));
    cuda::CudaTrainer trainer(model, train);
    for (int i = 0; i < 300; ++i) trainer.step();
    trainer.sync_model();
    bake::BakeSettings s;
    s.resolution = 48;
    const bake::BakedGrid cpu = bake::bake_model(model, s);
    const auto field = make_bake_field(Backend::cuda, model);
    const bake::BakedGrid gpu = bake::bake_model(model, s, {}, field.get());
    std::printf("bake 48^3: CPU %zu voxels (%llu with density), GPU %zu (%llu)\n", cpu.size(),
                (unsigned long long)cpu.density_voxels, gpu.size(), (unsigned long long)gpu.density_voxels);
    ASSERT_GT(cpu.density_voxels, 100u);
    // A voxel at the threshold may fall either way under float rounding: allow a few in a thousand.
    EXPECT_NEAR(double(gpu.size()), double(cpu.size()), 0.003 * double(cpu.size()) + 2);
    if (gpu.coords != cpu.coords) return;  // the element-wise comparison needs the same voxels
    double max_sigma = 0, max_rgb = 0;
    for (size_t i = 0; i < cpu.size(); ++i) {
        max_sigma = std::max(max_sigma, std::fabs(double(gpu.sigma[i]) - cpu.sigma[i]) / std::max(1.0f, cpu.sigma[i]));
        for (int k = 0; k < 3; ++k) max_rgb = std::max(max_rgb, std::fabs(double(gpu.color[i][k]) - cpu.color[i][k]));
    }
    EXPECT_LT(max_sigma, 1e-4);
    EXPECT_LT(max_rgb, 1e-4);
}

}  // namespace
}  // namespace npt::nerf

namespace npt::nerf {
namespace {

// Running out of device memory is one line that says how much was asked for and what to lower.
TEST(NerfCuda, OutOfMemoryIsOneLineNamingTheSizeAndWhatToLower) {
    try {
        gpu::DeviceBuffer<float> huge(size_t(1) << 40, "the sample buffers", "training.cuda_batch_samples");
        FAIL() << "a 4 TiB allocation succeeded";
    } catch (const Error& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        EXPECT_NE(m.find("GPU out of memory"), std::string::npos) << m;
        EXPECT_NE(m.find("the sample buffers"), std::string::npos) << m;
        EXPECT_NE(m.find("4194304.0 MiB"), std::string::npos) << m;
        EXPECT_NE(m.find("lower training.cuda_batch_samples"), std::string::npos) << m;
    }
    // The device is still usable afterwards.
    gpu::DeviceBuffer<float> small(1024);
    EXPECT_EQ(small.size(), 1024u);
}

}  // namespace
}  // namespace npt::nerf
