#include "multicue/system/perceive_views.hpp"

#include <array>
#include <cmath>

#include "multicue/core/exceptions.hpp"
#include "multicue/recognition/part_graph_model.hpp"

namespace multicue {
namespace {

using Distribution = std::array<float, kNumCategories>;

// Each object point votes with its object's distribution (which already merges its parts'):
// on simulated clutter this fuses better than the parts' own distributions.
std::vector<Distribution> PointVotes(const PerceivedObject& o) {
    return std::vector<Distribution>(o.indices.size(), o.category.probabilities);
}

}  // namespace

void FuseViewCategories(const std::vector<const PointCloud*>& clouds,
                        const std::vector<Eigen::Isometry3f>& T_world_sensor,
                        std::vector<PerceiveResult>& results, const PerceiveParams& params,
                        const ViewFusionParams& fusion) {
    if (clouds.size() != results.size() || T_world_sensor.size() != results.size()) {
        throw InvalidArgument("view fusion: one cloud, pose and result per frame");
    }
    if (!(fusion.voxel_size > 0.0f) || !std::isfinite(fusion.voxel_size)) {
        throw InvalidArgument("view fusion: voxel_size must be > 0 and finite");
    }
    for (std::size_t f = 0; f < results.size(); ++f) {
        if (clouds[f] == nullptr || clouds[f]->size() != results[f].point_objects.size() ||
            results[f].point_categories.size() != clouds[f]->size()) {
            throw InvalidArgument("view fusion: frame " + std::to_string(f) +
                                  " does not match its result");
        }
        if (!T_world_sensor[f].matrix().allFinite()) {
            throw InvalidArgument("view fusion: pose of frame " + std::to_string(f) +
                                  " is not finite");
        }
    }
    VoxelVoteGrid grid(fusion.voxel_size);
    std::vector<std::vector<std::vector<Eigen::Vector3f>>> world(results.size());
    for (std::size_t f = 0; f < results.size(); ++f) {
        const PointCloud& cloud = *clouds[f];
        for (const auto& o : results[f].objects) {
            std::vector<Eigen::Vector3f> points;
            points.reserve(o.indices.size());
            for (Index i : o.indices) points.push_back(T_world_sensor[f] * cloud.points[i]);
            if (o.category.category != Category::kNone) grid.Add(points, PointVotes(o));
            world[f].push_back(std::move(points));
        }
    }
    for (std::size_t f = 0; f < results.size(); ++f) {
        PerceiveResult& r = results[f];
        std::vector<std::size_t> changed;
        for (std::size_t k = 0; k < r.objects.size(); ++k) {
            PerceivedObject& o = r.objects[k];
            if (o.category.category == Category::kNone) continue;
            Distribution sum{};
            for (std::size_t j = 0; j < o.indices.size(); ++j) {
                const Distribution v = grid.Votes(world[f][k][j]);
                float total = 0.0f;
                for (float x : v) total += x;
                if (!(total > 0.0f)) continue;
                for (std::size_t c = 0; c < kNumCategories; ++c) sum[c] += v[c] / total;
                r.point_categories[o.indices[j]] = static_cast<std::uint8_t>(ArgMaxCategory(v));
            }
            float total = 0.0f;
            for (float x : sum) total += x;
            if (!(total > 0.0f)) continue;
            for (float& x : sum) x /= total;
            const Category before = o.category.category;
            o.category.probabilities = sum;
            o.category.category = ArgMaxCategory(sum);
            o.category.confidence = sum[static_cast<std::size_t>(o.category.category)];
            if (o.category.category != before) changed.push_back(k);
        }
        if (!fusion.remodel || changed.empty()) continue;
        // The frame with normals as perceive computes them for its objects.
        PointCloud cloud = *clouds[f];
        Indices objects;
        for (const auto& o : r.objects)
            objects.insert(objects.end(), o.indices.begin(), o.indices.end());
        const PerceiveParams threaded = ApplyThreadCount(params);
        EnsureFrameNormals(cloud, objects, threaded.normals);
        const Eigen::Vector4f plane = r.support.found ? r.support.plane : Eigen::Vector4f::Zero();
        ModelObjects(cloud, r.objects, plane, threaded.models, changed);
    }
}

}  // namespace multicue
