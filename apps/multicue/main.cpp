// multicue command-line tool: one subcommand per job, files in, files and exit codes out.
// Exit codes: 0 success, 1 data error (unreadable or malformed file, empty cloud, failed write),
// 2 usage error (unknown option, missing argument, parameter out of range).

#include <malloc.h>

#include <csignal>
#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/version.hpp"

namespace {

constexpr int kDataError = 1;
constexpr int kUsageError = 2;

int Fail(int code, const std::string& message) {
    // One line, whatever the message holds.
    std::string line = message;
    for (auto& c : line) {
        if (c == '\n' || c == '\r') c = ' ';
    }
    std::fprintf(stderr, "multicue: error: %s\n", line.c_str());
    return code;
}

}  // namespace

int main(int argc, char** argv) {
    // A write beyond the file size limit (ulimit -f) then fails with EFBIG and is reported as a
    // failed write naming the file, instead of the signal killing the process mid-file.
    std::signal(SIGXFSZ, SIG_IGN);
    // Buffers of 4 MB and more are mapped from the system one by one and returned when freed.
    // Without a fixed threshold glibc raises it to the largest buffer freed so far, after which
    // the point, normal and tree buffers of a large cloud stay in the process once used (a
    // third of the peak memory of perceive on 10 million points).
    mallopt(M_MMAP_THRESHOLD, 4 << 20);
    CLI::App app{"multicue: multi-cue perception of table-top objects from 3D and RGB-D data"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("multicue ") + MULTICUE_VERSION_STRING);
    multicue::cli::GlobalOptions global;
    std::string log_level = "warning";
    app.add_option("--log-level", log_level, "debug, info, warning, error or off")
        ->capture_default_str();
    app.add_option("-j,--threads", global.threads, "worker threads (0 = all cores)")
        ->capture_default_str();

    multicue::cli::AddInfoCommand(app, global);
    multicue::cli::AddConvertCommand(app, global);
    multicue::cli::AddDownsampleCommand(app, global);
    multicue::cli::AddNormalsCommand(app, global);
    multicue::cli::AddOutliersCommand(app, global);
    multicue::cli::AddPerceiveCommand(app, global);
    multicue::cli::AddConfigCommand(app, global);
    multicue::cli::AddDemoCommand(app, global);
    multicue::cli::AddDbCommand(app, global);
    multicue::cli::AddRunCommand(app, global);
    multicue::cli::AddSimulateCommand(app, global);
    multicue::cli::AddSimulateKitchensCommand(*app.get_subcommand("simulate"), global);
    multicue::cli::AddFeaturesCommand(app, global);
    multicue::cli::AddMlCommands(app, global);
    multicue::cli::AddMeshCommand(app, global);
    multicue::cli::AddTrainCommand(app, global);
    multicue::cli::AddDatasetExtractCommand(app, global);
    multicue::cli::AddRegisterCommand(app, global);
    // `map`: maps built from several scans; `map kitchen` is the kitchen's semantic map.
    auto* map_command = multicue::cli::AddMapCommand(app, global);
    multicue::cli::AddMapKitchenCommand(*map_command, global);
    // Furniture by part configurations: `simulate furniture`, `map furniture`, `train furniture`
    // and `detect furniture`.
    multicue::cli::AddSimulateFurnitureCommand(*app.get_subcommand("simulate"), global);
    multicue::cli::AddMapFurnitureCommand(*map_command, global);
    multicue::cli::AddTrainFurnitureCommand(*app.get_subcommand("train"), global);
    multicue::cli::AddTrainFixturesCommand(*app.get_subcommand("train"), global);
    multicue::cli::AddTrainContainersCommand(*app.get_subcommand("train"), global);
    multicue::cli::AddTrainJointsCommand(*app.get_subcommand("train"), global);
    multicue::cli::AddDetectFurnitureCommand(app, global);

    app.parse_complete_callback([&] {
        multicue::SetLogLevel(multicue::ParseLogLevel(log_level));
        if (global.threads < 0) {
            throw multicue::InvalidArgument("--threads must be >= 0 (0 = all cores), got " +
                                            std::to_string(global.threads));
        }
    });

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        return Fail(kUsageError, std::string(e.what()) + " (run with --help for usage)");
    } catch (const multicue::InvalidArgument& e) {
        return Fail(kUsageError, e.what());
    } catch (const multicue::Error& e) {
        return Fail(kDataError, e.what());
    } catch (const std::bad_alloc&) {
        return Fail(kDataError, "out of memory");
    } catch (const std::exception& e) {
        return Fail(kDataError, e.what());
    }
    return 0;
}
