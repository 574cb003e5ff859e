#include "multicue/system/perceive_output.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/io/ply.hpp"

namespace multicue {
namespace {

// Shortest decimal form of a float (0.02f prints as 0.02, not 0.019999999552965164); NaN as null.
nlohmann::ordered_json Num(float v) {
    if (!std::isfinite(v)) return nullptr;
    return std::stod(fmt::format("{}", v));
}

nlohmann::ordered_json Vec(const Eigen::Vector3f& v) {
    return nlohmann::ordered_json::array({Num(v.x()), Num(v.y()), Num(v.z())});
}

nlohmann::ordered_json ModelJson(const ObjectModel& m) {
    nlohmann::ordered_json j;
    if (m.cylinder) {
        const auto& c = *m.cylinder;
        j["type"] = "cylinder";
        j["center"] = Vec(c.center);
        j["axis"] = Vec(c.axis);
        j["radius"] = Num(c.radius);
        j["height"] = Num(c.height);
        j["inlier_ratio"] = Num(c.inlier_ratio);
    } else if (m.box) {
        const auto& b = *m.box;
        j["type"] = "box";
        j["center"] = Vec(b.center);
        j["axes"] = nlohmann::ordered_json::array(
            {Vec(b.axes.col(0)), Vec(b.axes.col(1)), Vec(b.axes.col(2))});
        j["extents"] = Vec(b.extents);
        j["inlier_ratio"] = Num(b.inlier_ratio);
    } else if (m.rotational) {
        const auto& r = *m.rotational;
        j["type"] = "rotational";
        j["axis_point"] = Vec(r.origin);  // the contract's name for the origin
        j["axis"] = Vec(r.axis);
        auto profile = nlohmann::ordered_json::array();
        for (std::size_t k = 0; k < r.heights.size() && k < r.radii.size(); ++k) {
            profile.push_back({Num(r.heights[k]), Num(r.radii[k])});
        }
        j["profile"] = profile;
        j["inlier_ratio"] = Num(r.inlier_ratio);
    } else {
        j["type"] = "mesh";
        j["vertices"] = m.mesh.vertices.size();
        j["triangles"] = m.mesh.triangles.size();
        if (!m.replaced.empty()) {
            j["replaced"] = {{"type", m.replaced},
                             {"reason", m.replace_reason},
                             {"inlier_ratio", Num(m.replaced_inlier_ratio)}};
        }
    }
    if (m.attached_triangles > 0) {
        j["attached"] = {{"points", m.attached_points}, {"triangles", m.attached_triangles}};
    }
    return j;
}

nlohmann::ordered_json VerificationJson(const ObjectModel& m) {
    if (!m.verification) return nullptr;
    const auto& v = *m.verification;
    return {{"verified", Num(v.verified)},
            {"occluded", Num(v.occluded)},
            {"invalid", Num(v.invalid)},
            {"accepted", v.accepted}};
}

nlohmann::ordered_json GraspJson(const GraspSummary& g) {
    nlohmann::ordered_json j;
    nlohmann::ordered_json dims = nlohmann::ordered_json::object();
    for (const auto& [name, value] : g.dimensions) dims[name] = Num(value);
    j["dimensions"] = dims;
    j["axis"] = g.axis ? Vec(*g.axis) : nlohmann::ordered_json(nullptr);
    j["graspable_width"] = Num(g.graspable_width);
    return j;
}

}  // namespace

Color ObjectColor(int id) {
    // Golden-angle hues: neighbouring ids get clearly different colours.
    const float h = std::fmod(static_cast<float>(id) * 137.508f, 360.0f) / 60.0f;
    const float x = 1.0f - std::abs(std::fmod(h, 2.0f) - 1.0f);
    float r = 0, g = 0, b = 0;
    switch (static_cast<int>(h)) {
        case 0:
            r = 1, g = x;
            break;
        case 1:
            r = x, g = 1;
            break;
        case 2:
            g = 1, b = x;
            break;
        case 3:
            g = x, b = 1;
            break;
        case 4:
            r = x, b = 1;
            break;
        default:
            r = 1, b = x;
            break;
    }
    auto c = [](float v) { return static_cast<std::uint8_t>(40 + v * 200); };
    return Color{c(r), c(g), c(b), 255};
}

nlohmann::ordered_json PerceiveResultJson(
    const std::string& input_name, const PerceiveResult& result,
    const std::vector<std::pair<std::string, double>>& timings_ms) {
    nlohmann::ordered_json j;
    j["format"] = fmt::format("multicue.result/{}", kPerceiveOutputFormatVersion);
    j["input"] = input_name;
    j["points"] = result.points;
    j["categories"] = kCategoryNames;
    if (result.support.found) {
        nlohmann::ordered_json s;
        const auto& p = result.support.plane;
        s["plane"] = {Num(p.x()), Num(p.y()), Num(p.z()), Num(p.w())};
        s["inliers"] = result.support.inliers.size();
        s["hull"] = nlohmann::ordered_json::array();
        for (const auto& h : result.support.hull) s["hull"].push_back(Vec(h));
        j["support"] = s;
    } else {
        j["support"] = nullptr;
    }
    j["objects"] = nlohmann::ordered_json::array();
    for (const auto& o : result.objects) {
        nlohmann::ordered_json oj;
        oj["id"] = o.id;
        oj["category"] = CategoryName(o.category.category);
        oj["confidence"] = Num(o.category.confidence);
        if (o.category_from_model) oj["category_from"] = "model";
        nlohmann::ordered_json probs = nlohmann::ordered_json::object();
        for (std::size_t c = 1; c < kNumCategories; ++c) {
            probs[std::string(kCategoryNames[c])] = Num(o.category.probabilities[c]);
        }
        oj["probabilities"] = probs;
        oj["points"] = o.indices.size();
        oj["parts"] = o.parts.size();
        oj["centroid"] = Vec(o.centroid);
        oj["model"] = ModelJson(o.model);
        oj["verification"] = VerificationJson(o.model);
        oj["accepted"] = o.model.accepted;
        oj["grasp"] = GraspJson(o.model.grasp);
        j["objects"].push_back(oj);
    }
    nlohmann::ordered_json t = nlohmann::ordered_json::object();
    double total = 0.0;
    for (const auto& list : {result.timings_ms, timings_ms}) {
        for (const auto& [stage, ms] : list) {
            t[stage] = std::round(ms * 100.0) / 100.0;
            total += ms;
        }
    }
    t["total"] = std::round(total * 100.0) / 100.0;
    j["timings_ms"] = t;
    return j;
}

namespace {

// The labels cloud around `points` (the input's, copied or taken), with the layout of `input`.
PointCloud LabelsCloud(std::vector<Eigen::Vector3f> points, const PointCloud& input,
                       const PerceiveResult& result) {
    PointCloud labels;
    labels.points = std::move(points);
    labels.width = input.width;
    labels.height = input.height;
    labels.sensor_origin = input.sensor_origin;
    labels.sensor_orientation = input.sensor_orientation;
    // Written as PCL's `label` field (uint32), so that pcl::PointXYZL reads the object ids; the
    // `object` field beside it keeps readers of format 1 working.
    labels.labels = result.point_objects;
    ExtraField object{"object", 'U', 4, 1, {}};
    object.data.resize(labels.points.size() * 4);
    std::memcpy(object.data.data(), result.point_objects.data(), object.data.size());
    ExtraField category{"category", 'U', 1, 1, {}};
    category.data.assign(result.point_categories.begin(), result.point_categories.end());
    labels.extra_fields = {std::move(object), std::move(category)};
    return labels;
}

}  // namespace

PointCloud PerceiveLabelsCloud(const PointCloud& input, const PerceiveResult& result) {
    return LabelsCloud(input.points, input, result);
}

PointCloud PerceiveLabelsCloud(PointCloud&& input, const PerceiveResult& result) {
    std::vector<Eigen::Vector3f> points = std::move(input.points);
    PointCloud layout;
    layout.width = input.width;
    layout.height = input.height;
    layout.sensor_origin = input.sensor_origin;
    layout.sensor_orientation = input.sensor_orientation;
    input = PointCloud();  // normals, curvature and the other fields are released here
    return LabelsCloud(std::move(points), layout, result);
}

TriangleMesh PerceiveModelsMesh(const PerceiveResult& result) {
    TriangleMesh all;
    all.vertex_colors.clear();
    for (const auto& o : result.objects) {
        TriangleMesh m = o.model.mesh;
        m.vertex_normals.clear();
        m.vertex_labels.assign(m.vertices.size(), static_cast<std::uint32_t>(o.id));
        m.vertex_colors.assign(m.vertices.size(), ObjectColor(o.id));
        all.Append(m);
    }
    return all;
}

void WritePerceiveOutputs(const std::filesystem::path& dir, const nlohmann::ordered_json& result,
                          const PointCloud& labels, const TriangleMesh& models,
                          std::string_view report_html) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (!std::filesystem::is_directory(dir)) {
        throw IoError(fmt::format("{}: cannot create output folder{}", dir.string(),
                                  ec ? ": " + ec.message() : ""));
    }
    // Staging folders of writers that were killed (their process is gone) are removed.
    for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string name = it->path().filename().string();
        constexpr std::string_view kPrefix = ".multicue-staging-";
        if (name.rfind(kPrefix, 0) != 0) continue;
        const long pid = std::strtol(name.c_str() + kPrefix.size(), nullptr, 10);
        if (pid > 0 && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
            std::error_code remove_ec;
            std::filesystem::remove_all(it->path(), remove_ec);
        }
    }
    ec.clear();
    const auto staging = dir / fmt::format(".multicue-staging-{}", static_cast<long>(::getpid()));
    std::filesystem::remove_all(staging, ec);
    if (!std::filesystem::create_directory(staging, ec)) {
        throw IoError(fmt::format("{}: output folder is not writable{}", dir.string(),
                                  ec ? ": " + ec.message() : ""));
    }
    std::vector<const char*> names = {"result.json", "labels.pcd", "models.ply"};
    if (!report_html.empty()) names.push_back("report.html");
    try {
        const std::string text = result.dump(1) + "\n";
        io::WriteFileAtomically(staging / names[0], [&](std::ostream& out) { out << text; });
        // Uncompressed: LZF would cost more time than the 4 MB it saves on a 640x480 frame.
        io::WritePcd(staging / names[1], labels, {.encoding = io::PcdEncoding::kBinary});
        io::WritePlyMesh(staging / names[2], models);
        if (!report_html.empty()) {
            io::WriteFileAtomically(staging / names[3],
                                    [&](std::ostream& out) { out << report_html; });
        }
        for (const char* name : names) {
            std::filesystem::rename(staging / name, dir / name, ec);
            if (ec) {
                throw IoError(fmt::format("{}: cannot move into place: {}", (dir / name).string(),
                                          ec.message()));
            }
        }
    } catch (...) {
        std::filesystem::remove_all(staging, ec);
        throw;
    }
    std::filesystem::remove_all(staging, ec);
}

}  // namespace multicue
