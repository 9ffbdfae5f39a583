// The nerfpt command line: global options, one subcommand per file (cmd_*.cpp), and the one place where
// errors become a single line on stderr and an exit code (0 ok, 1 error, 2 usage error, 128+signal when
// interrupted).
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "cmd_bake.h"
#include "cmd_capture.h"
#include "cmd_compare.h"
#include "cmd_curate.h"
#include "cmd_eval.h"
#include "cmd_import_ngp.h"
#include "cmd_info.h"
#include "cmd_isolate.h"
#include "cmd_pose_error.h"
#include "cmd_poses.h"
#include "cmd_render.h"
#include "cmd_serve.h"
#include "cmd_train.h"
#include "cmd_view.h"
#include "common.h"
#include "core/error.h"
#include "core/log.h"
#include "interrupt.h"
#include "option_checks.h"

namespace {

constexpr int k_exit_error = 1;
constexpr int k_exit_usage = 2;

void print_error(const char* message) { fmt::print(stderr, "nerfpt: error: {}\n", message); }

}  // namespace

int main(int argc, char** argv) {
    using namespace npt::cli;
    InterruptGuard interrupts;  // first: every thread started later inherits the blocked signals

    CLI::App app("nerfpt: train NeRFs from posed photos and path-trace glTF scenes.", "nerfpt");
    app.footer("Run 'nerfpt SUBCOMMAND --help' for the options of each subcommand.");
    app.set_version_flag("--version", std::string("nerfpt ") + k_version, "Print the version and exit");
    app.require_subcommand(1, 1);
    app.fallthrough();  // global options may also follow the subcommand: nerfpt render -q ...
    GlobalSettings global;
    app.add_flag("-v,--verbose", global.verbose, "Print debug messages (loading details, timings)");
    app.add_flag("-q,--quiet", global.quiet, "Print errors only: no progress, no info messages")
        ->excludes(app.get_option("--verbose"));
    RenderArgs render_args;
    CLI::App* render_cmd = add_render_command(app, render_args);
    InfoArgs info_args;
    CLI::App* info_cmd = add_info_command(app, info_args);
    CompareArgs compare_args;
    CLI::App* compare_cmd = add_compare_command(app, compare_args);
    TrainArgs train_args;
    CLI::App* train_cmd = add_train_command(app, train_args);
    EvalArgs eval_args;
    CLI::App* eval_cmd = add_eval_command(app, eval_args);
    ViewArgs view_args;
    CLI::App* view_cmd = add_view_command(app, view_args);
    BakeArgs bake_args;
    CLI::App* bake_cmd = add_bake_command(app, bake_args);
    ImportNgpArgs import_ngp_args;
    CLI::App* import_ngp_cmd = add_import_ngp_command(app, import_ngp_args);
    CurateArgs curate_args;
    CLI::App* curate_cmd = add_curate_command(app, curate_args);
    PosesArgs poses_args;
    CLI::App* poses_cmd = add_poses_command(app, poses_args);
    CaptureArgs capture_args;
    CLI::App* capture_cmd = add_capture_command(app, capture_args);
    PoseErrorArgs pose_error_args;
    CLI::App* pose_error_cmd = add_pose_error_command(app, pose_error_args);
    IsolateArgs isolate_args;
    CLI::App* isolate_cmd = add_isolate_command(app, isolate_args);
    ServeArgs serve_args;
    CLI::App* serve_cmd = add_serve_command(app, serve_args);
    check_numbers_strictly(app);  // NaN, "-1" for an unsigned, octal: refused for every option at once

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        print_error((std::string(e.what()) + " (see 'nerfpt --help')").c_str());
        return k_exit_usage;
    }

    npt::init_logging(global.verbosity());
    try {
        if (render_cmd->parsed()) return run_render(render_args, global, interrupts);
        if (info_cmd->parsed()) return run_info(info_args, global);
        if (compare_cmd->parsed()) return run_compare(compare_args, global);
        if (train_cmd->parsed()) return run_train(train_args, global, interrupts);
        if (eval_cmd->parsed()) return run_eval(eval_args, global, interrupts);
        if (view_cmd->parsed()) return run_view(view_args, global, interrupts);
        if (bake_cmd->parsed()) return run_bake(bake_args, global, interrupts);
        if (import_ngp_cmd->parsed()) return run_import_ngp(import_ngp_args, global);
        if (curate_cmd->parsed()) return run_curate(curate_args, global);
        if (poses_cmd->parsed()) return run_poses(poses_args, global, interrupts);
        if (capture_cmd->parsed()) return run_capture(capture_args, global, interrupts);
        if (pose_error_cmd->parsed()) return run_pose_error(pose_error_args, global);
        if (isolate_cmd->parsed()) return run_isolate(isolate_args, global);
        if (serve_cmd->parsed()) return run_serve(serve_args, global, interrupts);
    } catch (const npt::Error& e) {
        print_error(e.what());
        return k_exit_error;
    } catch (const std::bad_alloc&) {
        // The large allocations an input or option decides name themselves (core/memory.h); this is the rest.
        print_error(
            "out of memory: the input or the options ask for more memory than this machine has "
            "(lower --res, --spp, image sizes or the config's sizes)");
        return k_exit_error;
    } catch (const std::exception& e) {
        // Not one of ours (bad_alloc, a library's exception): still one line, with its type unspoken.
        print_error(e.what());
        return k_exit_error;
    }
    return k_exit_usage;  // unreachable: require_subcommand(1, 1) guarantees one of the above
}
