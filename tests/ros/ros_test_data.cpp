// The library side of the node test (C++20):
//   ros_test_data frames OUT_DIR N SHARED_DATA_DIR
//       N frames (mOSD learning scenes, else simulated views) as ROS 1 serialised PointCloud2
//       files OUT_DIR/frame_<k>.ros1
//   ros_test_data compare CLI_OUT GOT_DIR MIN_FRAMES
//       every labelled cloud, marker set and result the node published (ros_test_tool collect)
//       against `multicue perceive --bag` of the same bag: same points, object and category per
//       point, one text marker per object at its centroid with its category, as many model
//       triangles as models.ply, the same objects in result.json; at least MIN_FRAMES compared

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "bag_frames.hpp"
#include "multicue/io/point_cloud2.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/io/ros_messages.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace multicue {
namespace {

std::vector<std::uint8_t> ReadBytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
json ReadJson(const fs::path& p) {
    std::ifstream in(p);
    return json::parse(in);
}

int Frames(const fs::path& out, int n, const std::string& shared) {
    fs::create_directories(out);
    int k = 0;
    for (const auto& cloud : test::BagTestFrames(n, shared)) {
        auto msg = io::ToPointCloud2(cloud);
        msg.frame_id = "camera_rgb_optical_frame";
        const auto bytes = io::EncodePointCloud2Ros1(msg);
        std::ofstream file(out / fmt::format("frame_{:03d}.ros1", k++), std::ios::binary);
        file.write(reinterpret_cast<const char*>(bytes.data()),
                   static_cast<std::streamsize>(bytes.size()));
    }
    std::printf("%d frames of %s\n", k,
                fs::exists(fs::path(shared) / "scans/mosd-learn") ? "mOSD" : "the simulator");
    return 0;
}

/// Mismatches of one frame, printed; the count.
int CompareFrame(const fs::path& cli, const fs::path& got, const std::string& stamp) {
    int bad = 0;
    const auto fail = [&](const std::string& what) {
        std::printf("  %s: %s\n", stamp.c_str(), what.c_str());
        ++bad;
    };
    const fs::path ref = cli / stamp;
    if (!fs::exists(ref / "result.json")) {
        fail("the CLI has no result for this stamp");
        return bad;
    }
    const json result = ReadJson(ref / "result.json");
    const PointCloud expected = io::ReadPointCloud(ref / "labels.pcd");
    const PointCloud labels = io::FromPointCloud2(
        io::DecodePointCloud2Ros1(ReadBytes(got / (stamp + ".labels.ros1")), stamp), stamp);
    if (labels.size() != expected.size() || labels.width != expected.width) {
        fail(fmt::format("{} points ({} wide), the CLI {} ({} wide)", labels.size(), labels.width,
                         expected.size(), expected.width));
        return bad;
    }
    std::size_t point_diffs = 0;
    for (std::size_t i = 0; i < labels.size(); ++i) {
        const bool same = (labels.IsFinite(i) == expected.IsFinite(i)) &&
                          (!labels.IsFinite(i) || labels.points[i] == expected.points[i]);
        point_diffs += same ? 0 : 1;
    }
    if (point_diffs > 0) fail(fmt::format("{} points differ", point_diffs));
    if (labels.labels != expected.labels) fail("object ids per point differ");
    const auto* cat_a = labels.FindExtraField("category");
    const auto* cat_b = expected.FindExtraField("category");
    if (cat_a == nullptr || cat_b == nullptr || cat_a->data != cat_b->data)
        fail("categories per point differ");

    const json markers = ReadJson(got / (stamp + ".markers.json"));
    const auto& objects = result.at("objects");
    if (markers["texts"].size() != objects.size()) {
        fail(fmt::format("{} text markers, {} objects", markers["texts"].size(), objects.size()));
    } else {
        for (std::size_t k = 0; k < objects.size(); ++k) {
            const auto& t = markers["texts"][k];
            const auto& o = objects[k];
            bool ok = t["id"] == o["id"] &&
                      t["text"].get<std::string>().find(o["category"].get<std::string>()) !=
                          std::string::npos;
            for (int d = 0; d < 3; ++d)
                ok = ok && std::abs(t["position"][d].get<double>() -
                                    o["centroid"][d].get<double>()) < 1e-5;
            if (!ok) fail(fmt::format("marker {} differs from object {}", t.dump(), o.dump()));
        }
    }
    const TriangleMesh models = io::ReadTriangleMesh(ref / "models.ply");
    if (markers["triangles"].get<std::size_t>() != models.triangles.size()) {
        fail(fmt::format("{} model triangles, models.ply {}", markers["triangles"].dump(),
                         models.triangles.size()));
    }
    if (markers["frame_id"] != "camera_rgb_optical_frame") fail("markers lost the frame id");
    const json published = ReadJson(got / (stamp + ".result.json"));
    if (published["objects"].size() != objects.size()) fail("result objects differ");
    for (std::size_t k = 0; k < objects.size() && k < published["objects"].size(); ++k) {
        if (published["objects"][k]["category"] != objects[k]["category"] ||
            published["objects"][k]["points"] != objects[k]["points"])
            fail("result object " + std::to_string(k + 1) + " differs");
    }
    std::printf("  %s: %zu points, %zu objects, %zu triangles: %s\n", stamp.c_str(), labels.size(),
                objects.size(), models.triangles.size(),
                bad == 0 ? "same as the CLI" : "DIFFERENT");
    return bad;
}

int Compare(const fs::path& cli, const fs::path& got, int min_frames) {
    int compared = 0, bad = 0;
    std::vector<std::string> stamps;
    for (const auto& e : fs::directory_iterator(got)) {
        const std::string name = e.path().filename().string();
        const std::string suffix = ".labels.ros1";
        if (name.size() > suffix.size() &&
            name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
            stamps.push_back(name.substr(0, name.size() - suffix.size()));
    }
    std::sort(stamps.begin(), stamps.end());
    for (const auto& s : stamps) {
        bad += CompareFrame(cli, got, s);
        ++compared;
    }
    std::printf("compared %d published frames with the CLI: %d mismatches\n", compared, bad);
    return bad == 0 && compared >= min_frames ? 0 : 1;
}

}  // namespace
}  // namespace multicue

int main(int argc, char** argv) {
    const std::vector<std::string> a(argv + 1, argv + argc);
    try {
        if (a.size() == 4 && a[0] == "frames") return multicue::Frames(a[1], std::stoi(a[2]), a[3]);
        if (a.size() == 4 && a[0] == "compare")
            return multicue::Compare(a[1], a[2], std::stoi(a[3]));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "ros_test_data: %s\n", e.what());
        return 1;
    }
    std::fprintf(stderr, "usage: see the comment at the top of ros_test_data.cpp\n");
    return 2;
}
