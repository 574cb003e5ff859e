/// \file mosd_peers: segments mOSD scenes with three standard PCL 1.13 table-top pipelines and
/// writes OUT_DIR/<scene>/labels.pcd in the format of `multicue perceive` (fields x y z label
/// object category, same WIDTH/HEIGHT and point order as the input, label = object, 0 = no object,
/// category 0), so that the mOSD scorer (osd_eval.py) scores PCL on exactly the scenes multicue is
/// scored on.
///
/// usage: mosd_peers --method euclidean|region_growing|lccp INPUT_DIR OUT_DIR
///                   [--scenes learn0,learn1,...]
///
/// The pipelines use the parameters of PCL's own tutorials and examples (see eval/README.md):
///  - euclidean: the "Euclidean Cluster Extraction" tutorial (cluster_extraction.cpp);
///  - region_growing: the "Region growing segmentation" tutorial (region_growing_segmentation.cpp);
///  - lccp: PCL's LCCP example program (examples/segmentation/example_lccp_segmentation.cpp).
/// The time printed per scene is the wall time of the segmentation alone (from the loaded cloud to
/// the per-point object ids), without reading and writing files.

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include "driver_options.hpp"
#include "peers/segmentation.hpp"

namespace {

namespace fs = std::filesystem;

using multicue::peers::PeerSegmentation;
using Point = multicue::peers::PeerPoint;
using Cloud = multicue::peers::PeerCloud;

// labels.pcd: x y z (F4) label (U4) object (U4) category (U1), binary_compressed, input layout
// and order; label and object are the same id (result format 2).
bool WriteLabels(const fs::path& path, const Cloud& cloud,
                 const std::vector<std::uint32_t>& object) {
    pcl::PCLPointCloud2 out;
    out.width = cloud.width;
    out.height = cloud.height;
    out.is_dense = cloud.is_dense;
    auto field = [](const char* name, std::uint32_t offset, std::uint8_t type) {
        pcl::PCLPointField f;
        f.name = name;
        f.offset = offset;
        f.datatype = type;
        f.count = 1;
        return f;
    };
    out.fields = {field("x", 0, pcl::PCLPointField::FLOAT32),
                  field("y", 4, pcl::PCLPointField::FLOAT32),
                  field("z", 8, pcl::PCLPointField::FLOAT32),
                  field("label", 12, pcl::PCLPointField::UINT32),
                  field("object", 16, pcl::PCLPointField::UINT32),
                  field("category", 20, pcl::PCLPointField::UINT8)};
    out.point_step = 21;
    out.row_step = out.point_step * out.width;
    out.data.assign(static_cast<std::size_t>(out.point_step) * cloud.size(), 0);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        std::uint8_t* dst = out.data.data() + i * out.point_step;
        const Point& p = cloud[i];
        std::memcpy(dst, &p.x, 4);
        std::memcpy(dst + 4, &p.y, 4);
        std::memcpy(dst + 8, &p.z, 4);
        std::memcpy(dst + 12, &object[i], 4);
        std::memcpy(dst + 16, &object[i], 4);
        // category (byte 20) stays 0: the peers do not categorise.
    }
    pcl::PCDWriter writer;
    return writer.writeBinaryCompressed(path.string(), out, cloud.sensor_origin_,
                                        cloud.sensor_orientation_) == 0;
}

// learn2 before learn10: prefix, then the trailing number.
bool SceneLess(const std::string& a, const std::string& b) {
    auto split = [](const std::string& s) {
        std::size_t d = s.size();
        while (d > 0 && std::isdigit(static_cast<unsigned char>(s[d - 1]))) --d;
        const long number = d < s.size() ? std::stol(s.substr(d)) : -1;
        return std::make_pair(s.substr(0, d), number);
    };
    return split(a) < split(b);
}

}  // namespace

int main(int argc, char** argv) {
    std::string method;
    std::string scenes_arg;
    std::string input_arg, out_arg;
    CLI::App app{
        "mosd_peers: mOSD scenes segmented by PCL's table-top pipelines; reads "
        "INPUT_DIR/<scene>.pcd and writes OUT_DIR/<scene>/labels.pcd for the mOSD scorer"};
    app.add_option("--method", method, "PCL pipeline")
        ->required()
        ->check(CLI::IsMember({"euclidean", "region_growing", "lccp"}));
    app.add_option("--scenes", scenes_arg, "scenes to segment, learn0,learn1,... (default: all)");
    app.add_option("INPUT_DIR", input_arg, "folder of the scenes' .pcd files")->required();
    app.add_option("OUT_DIR", out_arg, "output folder")->required();
    if (auto code =
            multicue::eval::ParseDriverOptions(app, "mosd_peers", [&] { app.parse(argc, argv); }))
        return *code;
    PeerSegmentation (*segment)(const Cloud::ConstPtr&) =
        method == "euclidean"        ? multicue::peers::SegmentEuclidean
        : method == "region_growing" ? multicue::peers::SegmentRegionGrowing
                                     : multicue::peers::SegmentLccp;
    const fs::path input_dir = input_arg;
    const fs::path out_dir = out_arg;

    std::vector<std::string> scenes = multicue::eval::SplitComma(scenes_arg);
    if (scenes.empty()) {
        std::error_code ec;
        for (const auto& entry : fs::directory_iterator(input_dir, ec)) {
            if (entry.is_regular_file() && entry.path().extension() == ".pcd")
                scenes.push_back(entry.path().stem().string());
        }
        if (ec) {
            std::fprintf(stderr, "cannot list %s: %s\n", input_dir.c_str(), ec.message().c_str());
            return 1;
        }
        std::sort(scenes.begin(), scenes.end(), SceneLess);
    }
    if (scenes.empty()) {
        std::fprintf(stderr, "no scenes in %s\n", input_dir.c_str());
        return 1;
    }

    // PCL's warnings (e.g. about the unread label field) would drown the timings.
    pcl::console::setVerbosityLevel(pcl::console::L_ERROR);

    std::printf("%-10s %12s %8s   (method %s)\n", "scene", "segment_ms", "objects", method.c_str());
    std::vector<double> times_ms;
    int failures = 0;
    for (const auto& scene : scenes) {
        const fs::path in_path = input_dir / (scene + ".pcd");
        auto cloud = std::make_shared<Cloud>();
        if (pcl::io::loadPCDFile(in_path.string(), *cloud) < 0) {
            std::fprintf(stderr, "%s: cannot read %s\n", scene.c_str(), in_path.c_str());
            ++failures;
            continue;
        }
        PeerSegmentation result;
        const auto start = std::chrono::steady_clock::now();
        try {
            result = segment(cloud);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "%s: segmentation failed: %s\n", scene.c_str(), e.what());
            ++failures;
            continue;
        }
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        times_ms.push_back(ms);

        const fs::path scene_dir = out_dir / scene;
        std::error_code ec;
        fs::create_directories(scene_dir, ec);
        if (ec || !WriteLabels(scene_dir / "labels.pcd", *cloud, result.object)) {
            std::fprintf(stderr, "%s: cannot write %s\n", scene.c_str(),
                         (scene_dir / "labels.pcd").c_str());
            ++failures;
            continue;
        }
        std::printf("%-10s %12.1f %8zu\n", scene.c_str(), ms, result.objects);
        std::fflush(stdout);
    }
    if (!times_ms.empty()) {
        std::vector<double> sorted = times_ms;
        std::sort(sorted.begin(), sorted.end());
        const std::size_t n = sorted.size();
        const double median = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
        std::printf("median segmentation time: %.1f ms over %zu scenes (method %s)\n", median, n,
                    method.c_str());
    }
    return failures == 0 ? 0 : 1;
}
