// `multicue register SOURCE TARGET`: the transform that aligns one scan to another (ICP variants,
// points and planes, global alignment from planes or features), written as JSON; optionally the
// source moved into the target's frame.

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.hpp"
#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/registration/register.hpp"
#include "registration_json.hpp"

namespace multicue::cli {
namespace {

struct RegisterOptions {
    std::string source, target, out, aligned, init, method = "auto";
    float resolution = 0.0f;
    std::string depth_noise = "auto";
    bool quiet = false;
};

// --init: a JSON file of `register` (its T_target_source), a text file of 12 or 16 numbers
// (rows of the matrix), or 12 or 16 comma-separated numbers.
Eigen::Isometry3d ParseInit(const std::string& text) {
    std::string numbers = text;
    if (std::filesystem::is_regular_file(text)) {
        const std::string content = io::ReadFileBytes(text);
        const auto first = content.find_first_not_of(" \t\r\n");
        if (first != std::string::npos && content[first] == '{') {
            try {
                return TransformFromJson(nlohmann::json::parse(content).at("T_target_source"));
            } catch (const nlohmann::json::exception& e) {
                throw FormatError(fmt::format("{}: no 4x4 T_target_source ({})", text, e.what()));
            }
        }
        numbers = content;
    }
    for (auto& c : numbers) {
        if (c == ',' || c == '[' || c == ']' || c == ';') c = ' ';
    }
    std::istringstream in(numbers);
    std::vector<double> v;
    double x = 0.0;
    while (in >> x) v.push_back(x);
    if (!in.eof() || (v.size() != 12 && v.size() != 16)) {
        throw InvalidArgument(fmt::format(
            "--init: expected 12 or 16 numbers (rows of a 3x4 or 4x4 matrix) or a file with them, "
            "got '{}'",
            text.substr(0, 80)));
    }
    Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
    for (std::size_t k = 0; k < v.size(); ++k)
        M(static_cast<int>(k / 4), static_cast<int>(k % 4)) = v[k];
    return CheckedTransform(M, "--init");
}

void Run(const RegisterOptions& o, int threads) {
    CheckDistinctPaths(o.source, o.out);
    CheckDistinctPaths(o.target, o.out);
    if (!o.aligned.empty()) CheckDistinctPaths(o.source, o.aligned);
    const RegistrationMethod method = ParseRegistrationMethod(o.method);
    std::optional<Eigen::Isometry3d> init;
    if (!o.init.empty()) init = ParseInit(o.init);
    if (!(o.resolution >= 0.0f) || !std::isfinite(o.resolution)) {
        throw InvalidArgument(fmt::format("--resolution must be > 0, got {}", o.resolution));
    }
    const PointCloud source = ReadNonEmptyCloud(o.source);
    const PointCloud target = ReadNonEmptyCloud(o.target);
    RegistrationParams params = o.resolution > 0.0f
                                    ? RegistrationParams::ForResolution(o.resolution)
                                    : SuggestRegistrationParams(target);
    if (o.depth_noise == "auto") {
        if (o.resolution > 0.0f)
            params.icp.depth_noise = SuggestRegistrationParams(target).icp.depth_noise;
    } else {
        params.icp.depth_noise = ParseFloatOption(o.depth_noise, "--depth-noise");
    }
    params.method = method;
    params.num_threads = threads;
    const RegistrationResult r = Register(source, target, params, init);
    nlohmann::ordered_json result = RegistrationJson(r);
    result["source"] = o.source;
    result["target"] = o.target;
    result["method"] = RegistrationMethodName(method);
    result["resolution"] = params.preprocess.voxel_size;
    const std::string text = result.dump(1) + "\n";
    io::WriteFileAtomically(o.out, [&](std::ostream& s) { s << text; });
    if (!r.converged) {
        throw DataError(
            fmt::format("registration of {} to {} did not converge ({}: {}); details in {}",
                        o.source, o.target, RegistrationStatusName(r.status), r.reason, o.out));
    }
    if (!o.aligned.empty()) {
        PointCloud moved = source;
        const Eigen::Isometry3f T = r.T_target_source.cast<float>();
        for (auto& p : moved.points) p = T * p;
        for (auto& n : moved.normals) n = T.linear() * n;
        moved.sensor_origin = T * source.sensor_origin;
        moved.SetUnorganized();  // a moved frame is no longer on its pixel grid
        io::WritePointCloud(o.aligned, moved);
    }
    if (!o.quiet) {
        const auto& t = r.T_target_source.translation();
        std::printf(
            "converged: %s\nrotation %.3f deg, translation (%.4f, %.4f, %.4f) m\n"
            "fitness %.3f, overlap %.3f, inlier RMSE %.4f m, %d iterations, %.0f ms\n"
            "outputs: %s%s%s\n",
            r.reason.c_str(), RotationAngleDeg(r.T_target_source), t.x(), t.y(), t.z(), r.fitness,
            r.overlap, r.inlier_rmse, r.iterations, r.time_ms, o.out.c_str(),
            o.aligned.empty() ? "" : ", ", o.aligned.c_str());
    }
}

}  // namespace

void AddRegisterCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "register", "Align SOURCE to TARGET: ICP variants, points and planes, global alignment");
    auto o = std::make_shared<RegisterOptions>();
    cmd->add_option("SOURCE", o->source, "scan to move (.pcd or .ply)")->required();
    cmd->add_option("TARGET", o->target, "scan to align to")->required();
    cmd->add_option(
           "--method", o->method,
           "icp (point-to-point), point-to-plane, symmetric, plane (points and planes), "
           "global (no guess needed), auto (plane with --init, global if that fails or without "
           "--init)")
        ->capture_default_str();
    cmd->add_option("--init", o->init,
                    "initial guess of T_target_source: 12 or 16 comma-separated numbers (rows), "
                    "a text file with them, or the JSON of an earlier `register`");
    cmd->add_option("--out", o->out, "the result as JSON (T_target_source, converged, ...)")
        ->required();
    cmd->add_option("--aligned", o->aligned, "SOURCE moved into TARGET's frame (.pcd or .ply)");
    cmd->add_option("--resolution", o->resolution,
                    "voxel size and scale of every distance [m] (default: 1 cm for depth frames, "
                    "else from the point spacing)");
    cmd->add_option("--depth-noise", o->depth_noise,
                    "depth noise sigma / depth^2 [1/m] weighting the pairs; auto: 0.0014 for "
                    "organized depth frames, 0 otherwise")
        ->capture_default_str();
    cmd->add_flag("-q,--quiet", o->quiet, "print nothing on success");
    cmd->callback([o, &global] { Run(*o, global.threads); });
}

}  // namespace multicue::cli
