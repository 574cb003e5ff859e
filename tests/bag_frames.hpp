#pragma once
// The frames the bag tests record: the first mOSD learning scenes when the shared data is there,
// else simulated Kinect views of table scenes (the sim module), so the tests run everywhere.

#include <string>
#include <vector>

#include "multicue/io/point_cloud_io.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"

namespace multicue::test {

inline std::vector<PointCloud> BagTestFrames(int n, const std::string& shared_data_dir) {
    std::vector<PointCloud> frames;
    for (int k = 0; k < n; ++k) {
        const std::filesystem::path mosd = std::filesystem::path(shared_data_dir) /
                                           "scans/mosd-learn" /
                                           ("learn" + std::to_string(k) + ".pcd");
        if (std::filesystem::exists(mosd)) {
            frames.push_back(io::ReadPointCloud(mosd));
            continue;
        }
        sim::TableSceneParams table;
        table.min_objects = table.max_objects = 3;
        table.clutter = 0.0f;
        const std::uint64_t seed = sim::SubSeed(11, static_cast<std::uint64_t>(k));
        const sim::Scene scene = sim::MakeTableScene(table, seed);
        const auto pose = sim::TableViewpoints(scene, 1, {}, seed).front();
        frames.push_back(
            sim::ScanKinect(scene, pose, sim::KinectParams{}, sim::SubSeed(seed, 100)));
    }
    return frames;
}

}  // namespace multicue::test
