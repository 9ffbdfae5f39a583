#include "render_ranks.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>

#include "core/error.h"
#include "core/image_io.h"
#include "core/progress.h"
#include "dist/frames.h"
#include "interrupt.h"
#include "render/backend/render_backend.h"
#include "render/sample_sums.h"
#include "render_outputs.h"
#include "render_sequence.h"
#include "scene/scene.h"

namespace npt::cli {
namespace fs = std::filesystem;

namespace {

// Every rank went well so far, or (on every rank) stop: rank 0 prints the line naming the rank that failed.
void agree_or_stop(dist::MpiWorld& world, const std::string& error = {}) {
    if (const auto failure = world.agree(error)) {
        if (world.rank() == 0) fmt::print(stderr, "nerfpt: error: {}\n", *failure);
        throw dist::PeerFailed();
    }
}

int render_still_ranks(const RenderArgs& args, const GlobalSettings& global, InterruptGuard& interrupts,
                       dist::MpiWorld& world) {
    if (args.overwrite || args.fps > 0 || args.task_index >= 0 || args.task_count >= 0)
        throw Error(
            "--overwrite, --fps, --task-index and --task-count are for sequences (with --frames FIRST-LAST)");
    if (args.denoise)
        throw Error(
            "--denoise: not available when a still's samples are split over MPI ranks (run one process)");
    const bool leader = world.rank() == 0;
    const fs::path out_exr = args.output;
    fs::path out_png = out_exr;
    out_png.replace_extension(".png");
    check_output(out_exr);
    const uint32_t aov_mask = args.aovs.empty() ? 0u : render::parse_aov_list(args.aovs);
    const std::vector<AovFile> aov_files =
        args.aov_files ? aov_file_paths(out_exr, aov_mask) : std::vector<AovFile>{};

    render::RenderOptions options = render_options_from_args(args, aov_mask);
    const scene::Scene scene = scene::load_scene(args.scene, scene_load_options(args));
    for (const fs::path& out : {out_exr, out_png})
        refuse_overwriting_inputs(out, "--output", scene_inputs(scene));
    for (const AovFile& f : aov_files) refuse_overwriting_inputs(f.path, "--aov-files", scene_inputs(scene));
    options.seed = args.seed_given ? args.seed : scene.settings.seed;
    std::string note;
    options.backend = render::choose_render_backend(args.backend, &note);
    if (!note.empty()) spdlog::info("{}", note);
    const render::RenderOptions resolved = render::resolve_options(scene, options);
    const int n = world.size(), r = world.rank();
    const uint32_t begin = uint32_t(uint64_t(resolved.spp) * uint64_t(r) / uint64_t(n));
    const uint32_t end = uint32_t(uint64_t(resolved.spp) * uint64_t(r + 1) / uint64_t(n));
    spdlog::info(
        "rendering {}x{}, {} spp over {} MPI ranks (samples split), max depth {}, seed {}, backend {}{}{}",
        resolved.width, resolved.height, resolved.spp, n, resolved.max_depth, resolved.seed, resolved.backend,
        resolved.transparent ? ", transparent" : "", args.aovs.empty() ? "" : ", AOVs " + args.aovs);

    ProgressSettings ps;
    ps.style = progress_style(stream_is_tty(stderr), global.quiet || !leader);
    Progress progress(ps, std::cerr);
    const auto t0 = std::chrono::steady_clock::now();
    render::PartialFilm film;  // empty where a rank has no samples (spp < ranks)
    film.width = resolved.width;
    film.height = resolved.height;
    film.spp = uint32_t(resolved.spp);
    film.first_hits = resolved.transparent || aov_mask != 0;
    if (begin < end) {
        const auto renderer = render::prepare_renderer(scene, resolved);
        film = renderer->render_partial(resolved, begin, end, [&progress](uint64_t done, uint64_t total) {
            progress.update(done, total);
        });
    }
    progress.finish();
    const double render_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    agree_or_stop(world);

    // Every rank rendered its samples: their sums, merged in sample order, to rank 0.
    std::vector<char> bytes = render::partial_to_bytes(film);
    world.reduce_in_rank_order(bytes, [](std::vector<char>& left, std::vector<char>&& right) {
        render::PartialFilm merged = render::partial_from_bytes(left);
        render::merge_partial(merged, render::partial_from_bytes(right));
        left = render::partial_to_bytes(merged);
    });
    if (!leader) return 0;
    film = render::partial_from_bytes(bytes);
    bytes = {};
    render::AovImages aovs;
    const Image image = render::resolve_partial(film, resolved.transparent ? 4 : 3, aov_mask, &aovs);
    if (film.dropped > 0)
        spdlog::warn("render: {} samples were NaN or infinite and were dropped", film.dropped);
    {
        auto no_interrupt = interrupts.hold();  // every file complete, or an interrupt waits for them
        write_exr_layers(out_exr, image, aov_layers(aovs, aov_mask));
        write_render_png(out_png, image, args.exposure);
        for (const AovFile& f : aov_files) write_aov_file(f, aovs);
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    fmt::print("wrote {}\nwrote {}\n", out_exr.string(), out_png.string());
    for (const AovFile& f : aov_files) fmt::print("wrote {}\n", f.path.string());
    fmt::print(
        "rendered {}x{} at {} spp over {} ranks in {} (rank 0's samples: {}; {} samples/s)\n", resolved.width,
        resolved.height, resolved.spp, n, format_seconds(seconds), format_seconds(render_s),
        format_count(seconds > 0 ? double(resolved.width) * resolved.height * resolved.spp / seconds : 0.0));
    return 0;
}

}  // namespace

int run_render_ranks(const RenderArgs& args, const GlobalSettings& global, InterruptGuard& interrupts,
                     dist::MpiWorld& world) {
    if (world.rank() != 0 && !global.verbose)
        spdlog::set_level(spdlog::level::warn);  // rank 0 speaks for the job
    if (!world.gpu_note().empty()) spdlog::debug("{}: {}", world.name(), world.gpu_note());
    int rc = 0;
    try {
        if (args.frames.empty()) {
            rc = render_still_ranks(args, global, interrupts, world);
        } else {
            FrameSharing sharing;
            sharing.rank_text = fmt::format("rank {} of {}: ", world.rank(), world.size());
            sharing.leader = world.rank() == 0;
            sharing.share = [&world](const std::vector<int>& todo) {
                agree_or_stop(world);
                std::vector<int> shared = todo;  // rank 0's: every rank splits the same list
                world.broadcast(shared);
                std::vector<int> mine = dist::task_frames(shared, world.rank(), world.size());
                if (world.rank() == 0 && !shared.empty())
                    spdlog::info("{} frames over {} MPI ranks, {} to {} each", shared.size(), world.size(),
                                 shared.size() / size_t(world.size()),
                                 (shared.size() + size_t(world.size()) - 1) / size_t(world.size()));
                return mine;
            };
            GlobalSettings rank_global = global;
            rank_global.quiet = global.quiet || world.rank() != 0;  // one progress bar: rank 0's
            rc = run_render_sequence(args, rank_global, interrupts, sharing);
        }
    } catch (const dist::PeerFailed&) {
        return 1;  // rank 0 said which rank failed
    } catch (const std::exception& e) {
        // This rank failed: the others learn it at their next agreement, rank 0 prints it.
        if (const auto failure = world.agree(e.what()); failure && world.rank() == 0)
            fmt::print(stderr, "nerfpt: error: {}\n", *failure);
        return 1;
    }
    // The last agreement: a rank that failed after the others' last step is still reported.
    if (const auto failure = world.agree({})) {
        if (world.rank() == 0) fmt::print(stderr, "nerfpt: error: {}\n", *failure);
        return 1;
    }
    return rc;
}

}  // namespace npt::cli
