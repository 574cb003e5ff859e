#include "multicue/features/pfh.hpp"

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"

namespace multicue {
namespace {

constexpr int kPfhSplit = 5;
constexpr int kFpfhBins = 11;
// PCL's constant 1 / (2 pi), in float as PCL keeps it, so that bin borders coincide.
const float kInvTwoPi = 1.0f / (2.0f * static_cast<float>(M_PI));

int AngleBin(float f1, int bins) {
    return detail::ClampedBin(bins * ((f1 + M_PI) * kInvTwoPi), bins);
}
int UnitBin(float f, int bins) { return detail::ClampedBin(bins * ((f + 1.0) * 0.5), bins); }
// PFHRGB computes the same in float (pfhrgb.hpp), which rounds differently at bin borders that
// colour ratios of small integers hit exactly.
int UnitBinF(float f, int bins) {
    const float v = static_cast<float>(bins) * ((f + 1.0f) * 0.5f);
    return detail::ClampedBin(v, bins);
}

void CheckInput(const PointCloud& cloud, const KdTree& tree, const PairFeatureParams& params,
                const char* feature) {
    detail::CheckPositive(params.radius, "radius");
    detail::CheckThreads(params.num_threads);
    detail::CheckNormals(cloud, feature);
    detail::CheckTree(cloud, tree);
}

// Drops neighbours without a usable normal; keeps the order.
void KeepUsable(const PointCloud& cloud, Indices& nn, std::vector<float>& d2) {
    std::size_t kept = 0;
    for (std::size_t k = 0; k < nn.size(); ++k) {
        if (!cloud.normals[nn[k]].allFinite()) continue;
        nn[kept] = nn[k];
        d2[kept] = d2[k];
        ++kept;
    }
    nn.resize(kept);
    d2.resize(kept);
}

// Runs body(i, neighbours, squared distances, row pointer) for every usable point; other rows
// become NaN.
template <typename Body>
FeatureMatrix ForEachNeighbourhood(const PointCloud& cloud, const KdTree& tree, float radius,
                                   int dims, int num_threads, Body&& body) {
    const std::size_t n = cloud.size();
    FeatureMatrix out = FeatureMatrix::Zero(static_cast<Eigen::Index>(n), dims);
    ParallelForChunks(
        n, num_threads,
        [&](std::size_t begin, std::size_t end) {
            Indices nn;
            std::vector<float> d2;
            for (std::size_t i = begin; i < end; ++i) {
                float* row = out.data() + i * static_cast<std::size_t>(dims);
                if (!detail::IsUsable(cloud, i)) {
                    std::fill(row, row + dims, std::numeric_limits<float>::quiet_NaN());
                    continue;
                }
                detail::RadiusNeighbours(tree, cloud.points[i], radius, nn, d2);
                KeepUsable(cloud, nn, d2);
                body(i, nn, d2, row);
            }
        },
        64);
    return out;
}

// PCL's increment 100 / (m (m - 1) / 2), the division done in integers as PCL does.
float PairIncrement(std::size_t m) {
    const std::size_t pairs = m * (m - 1) / 2;
    return pairs == 0 ? 0.0f : 100.0f / static_cast<float>(pairs);
}

}  // namespace

FeatureMatrix ComputePfh(const PointCloud& cloud, const KdTree& tree,
                         const PairFeatureParams& params) {
    CheckInput(cloud, tree, params, "PFH");
    return ForEachNeighbourhood(
        cloud, tree, params.radius, kPfhSize, params.num_threads,
        [&](std::size_t, const Indices& nn, const std::vector<float>&, float* hist) {
            const float incr = PairIncrement(nn.size());
            for (std::size_t a = 0; a < nn.size(); ++a) {
                const Eigen::Vector3f& pa = cloud.points[nn[a]];
                const Eigen::Vector3f& na = cloud.normals[nn[a]];
                for (std::size_t b = 0; b < a; ++b) {
                    float f1, f2, f3, f4;
                    if (!detail::PairFeatures(pa, na, cloud.points[nn[b]], cloud.normals[nn[b]], f1,
                                              f2, f3, f4)) {
                        continue;
                    }
                    const int bin =
                        AngleBin(f1, kPfhSplit) +
                        kPfhSplit * (UnitBin(f2, kPfhSplit) + kPfhSplit * UnitBin(f3, kPfhSplit));
                    hist[bin] += incr;
                }
            }
        });
}

FeatureMatrix ComputeFpfh(const PointCloud& cloud, const KdTree& tree,
                          const PairFeatureParams& params) {
    CheckInput(cloud, tree, params, "FPFH");
    // Pass 1: SPFH of every usable point (pairs of the point with each neighbour).
    const FeatureMatrix spfh = ForEachNeighbourhood(
        cloud, tree, params.radius, kFpfhSize, params.num_threads,
        [&](std::size_t i, const Indices& nn, const std::vector<float>&, float* hist) {
            if (nn.size() < 2) return;
            const float incr = 100.0f / static_cast<float>(nn.size() - 1);
            const Eigen::Vector3f& p = cloud.points[i];
            const Eigen::Vector3f& n = cloud.normals[i];
            for (Index j : nn) {
                if (j == i) continue;
                float f1, f2, f3, f4;
                if (!detail::PairFeatures(p, n, cloud.points[j], cloud.normals[j], f1, f2, f3,
                                          f4)) {
                    continue;
                }
                hist[AngleBin(f1, kFpfhBins)] += incr;
                hist[kFpfhBins + UnitBin(f2, kFpfhBins)] += incr;
                hist[2 * kFpfhBins + UnitBin(f3, kFpfhBins)] += incr;
            }
        });
    // Pass 2: neighbours' SPFHs weighted by 1 / squared distance, each block scaled to 100.
    return ForEachNeighbourhood(
        cloud, tree, params.radius, kFpfhSize, params.num_threads,
        [&](std::size_t, const Indices& nn, const std::vector<float>& d2, float* hist) {
            double sums[3] = {0.0, 0.0, 0.0};
            for (std::size_t k = 0; k < nn.size(); ++k) {
                if (d2[k] == 0.0f) continue;
                const float weight = 1.0f / d2[k];
                const float* s = spfh.data() + static_cast<std::size_t>(nn[k]) * kFpfhSize;
                for (int block = 0; block < 3; ++block) {
                    float block_sum = 0.0f;
                    for (int b = block * kFpfhBins; b < (block + 1) * kFpfhBins; ++b) {
                        const float v = s[b] * weight;
                        hist[b] += v;
                        block_sum += v;
                    }
                    sums[block] += block_sum;
                }
            }
            for (int block = 0; block < 3; ++block) {
                if (sums[block] == 0.0) continue;
                const double scale = 100.0 / sums[block];
                for (int b = block * kFpfhBins; b < (block + 1) * kFpfhBins; ++b) {
                    hist[b] = static_cast<float>(hist[b] * scale);
                }
            }
        });
}

FeatureMatrix ComputePfhRgb(const PointCloud& cloud, const KdTree& tree,
                            const PairFeatureParams& params) {
    CheckInput(cloud, tree, params, "PFHRGB");
    if (!cloud.empty() && !cloud.HasColors()) {
        throw InvalidArgument("PFHRGB needs colours: the cloud has none");
    }
    auto ratio = [](int a, int b) {
        float r = b != 0 ? static_cast<float>(a) / static_cast<float>(b) : 1.0f;
        return r > 1.0f ? -1.0f / r : r;
    };
    return ForEachNeighbourhood(
        cloud, tree, params.radius, kPfhRgbSize, params.num_threads,
        [&](std::size_t, const Indices& nn, const std::vector<float>&, float* hist) {
            const float incr = PairIncrement(nn.size());
            for (Index a : nn) {
                const Eigen::Vector3f& p1 = cloud.points[a];
                const Eigen::Vector3f& n1 = cloud.normals[a];
                const Color c1 = cloud.colors[a];
                for (Index b : nn) {
                    if (a == b) continue;
                    // Darboux frame at the first point of the ordered pair (no source swap).
                    const Eigen::Vector3f d = cloud.points[b] - p1;
                    const float dist = d.norm();
                    if (dist == 0.0f) continue;
                    const Eigen::Vector3f& n2 = cloud.normals[b];
                    Eigen::Vector3f v = d.cross(n1);
                    const float v_norm = v.norm();
                    if (v_norm == 0.0f) continue;
                    v /= v_norm;
                    const Eigen::Vector3f w = n1.cross(v);
                    const float f1 = std::atan2(w.dot(n2), n1.dot(n2));
                    const float f2 = v.dot(n2);
                    const float f3 = n1.dot(d) / dist;
                    const Color c2 = cloud.colors[b];
                    const int geo =
                        AngleBin(f1, kPfhSplit) +
                        kPfhSplit * (UnitBinF(f2, kPfhSplit) + kPfhSplit * UnitBinF(f3, kPfhSplit));
                    const int col =
                        UnitBinF(ratio(c1.r, c2.r), kPfhSplit) +
                        kPfhSplit * (UnitBinF(ratio(c1.g, c2.g), kPfhSplit) +
                                     kPfhSplit * UnitBinF(ratio(c1.b, c2.b), kPfhSplit));
                    hist[geo] += incr;
                    hist[kPfhSize + col] += incr;
                }
            }
        });
}

}  // namespace multicue
