#include "multicue/segmentation/region_growing.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>
#include <tuple>
#include <utility>

#include <fmt/format.h>

#include "multicue/core/disjoint_sets.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/search/nearest_keys.hpp"
#include "multicue/search/organized.hpp"

namespace multicue {
namespace {

void CheckParams(const RegionGrowingParams& params) {
    if (!(params.radius > 0.0f) || !std::isfinite(params.radius)) {
        throw InvalidArgument(
            fmt::format("region growing radius must be > 0, got {}", params.radius));
    }
    if (params.k < 0) {
        throw InvalidArgument(fmt::format("region growing k must be >= 0, got {}", params.k));
    }
    if (!(params.max_angle_deg > 0.0f && params.max_angle_deg <= 180.0f)) {
        throw InvalidArgument(
            fmt::format("max_angle_deg must be in (0, 180], got {}", params.max_angle_deg));
    }
}

void CheckFields(const PointCloud& cloud) {
    const std::size_t n = cloud.size();
    if (!cloud.HasNormals()) throw DataError("region growing needs normals; the cloud has none");
    if (!cloud.HasCurvature()) {
        throw DataError("region growing needs curvature; the cloud has none");
    }
    if (cloud.normals.size() != n) {
        throw DataError(
            fmt::format("the cloud has {} normals for {} points", cloud.normals.size(), n));
    }
    if (cloud.curvature.size() != n) {
        throw DataError(fmt::format("the cloud has {} curvature values for {} points",
                                    cloud.curvature.size(), n));
    }
}

// Neighbourhoods of the growth and merging phases: all points within the radius, or the k
// nearest of them, from a k-d tree or from the pixel window of an organized frame.
class Neighborhoods {
  public:
    virtual ~Neighborhoods() = default;
    /// Neighbours of point q (q included), nearest first; see indices() and squared_distances(),
    /// valid until the next search.
    virtual void Search(Index q) = 0;
    std::span<const Index> indices() const { return indices_; }
    std::span<const float> squared_distances() const { return squared_distances_; }

  protected:
    std::span<const Index> indices_;
    std::span<const float> squared_distances_;
};

// From a k-d tree. Checks that the tree indexes the query point and belongs to this cloud.
class TreeNeighborhoods final : public Neighborhoods {
  public:
    TreeNeighborhoods(const PointCloud& cloud, const KdTree& tree,
                      const RegionGrowingParams& params)
        : cloud_(cloud), tree_(tree), radius_(params.radius), k_(params.k) {}

    void Search(Index q) override {
        const Eigen::Vector3f& p = cloud_.points[q];
        bool self_may_be_left_out = false;
        if (k_ > 0) {
            tree_.SearchKnn(p, k_, found_, found_d2_);
            // With k or more copies of q, the k nearest may all be copies other than q itself.
            self_may_be_left_out =
                found_.size() == static_cast<std::size_t>(k_) && found_d2_.back() == 0.0f;
            const float radius_sq = radius_ * radius_;
            std::size_t keep = 0;
            while (keep < found_d2_.size() && found_d2_[keep] < radius_sq) ++keep;
            found_.resize(keep);
            found_d2_.resize(keep);
        } else {
            tree_.SearchRadius(p, radius_, found_, found_d2_);
        }
        bool found_self = self_may_be_left_out;
        for (Index j : found_) {
            if (j >= cloud_.size()) {
                throw InvalidArgument(
                    fmt::format("the k-d tree holds point {}, but the cloud has only {} points", j,
                                cloud_.size()));
            }
            found_self = found_self || j == q;
        }
        if (!found_self) {
            throw InvalidArgument(
                fmt::format("point {} is to be segmented but the k-d tree does not index it", q));
        }
        indices_ = found_;
        squared_distances_ = found_d2_;
    }

  private:
    const PointCloud& cloud_;
    const KdTree& tree_;
    float radius_;
    int k_;
    Indices found_;
    std::vector<float> found_d2_;
};

// From a table of precomputed neighbourhoods (rows of the points to segment).
class TableNeighborhoods final : public Neighborhoods {
  public:
    explicit TableNeighborhoods(const NeighbourTable& table) : table_(table) {}

    void Search(Index q) override {
        const std::uint32_t row = table_.row_of[q];
        const std::size_t begin = row * table_.stride;
        const std::size_t n = table_.count[row];
        indices_ = std::span<const Index>(table_.neighbours.data() + begin, n);
        squared_distances_ = std::span<const float>(table_.squared_distances.data() + begin, n);
    }

  private:
    const NeighbourTable& table_;
};

// Marks the points with finite coordinates, normal and curvature in the subset (or cloud).
std::size_t MarkPoints(const PointCloud& cloud, const Indices& subset,
                       std::vector<std::uint8_t>& active) {
    const std::size_t n = cloud.size();
    active.assign(n, 0);
    std::size_t count = 0;
    auto mark = [&](std::size_t i) {
        if (active[i] != 0) return;
        const Eigen::Vector3f& normal = cloud.normals[i];
        if (cloud.IsFinite(i) && normal.allFinite() && normal.squaredNorm() > 0.0f &&
            std::isfinite(cloud.curvature[i])) {
            active[i] = 1;
            ++count;
        }
    };
    if (subset.empty()) {
        for (std::size_t i = 0; i < n; ++i) mark(i);
        return count;
    }
    for (Index i : subset) {
        if (i >= n) {
            throw InvalidArgument(
                fmt::format("subset index {} is out of range for a cloud of {} points", i, n));
        }
        mark(i);
    }
    return count;
}

// Seeds by lowest curvature, so that flat parts are found first (section 4.2.1); ties by index.
// The marked points are looked for in `subset` when one is given (not in the whole cloud).
Indices SeedOrder(const PointCloud& cloud, const std::vector<std::uint8_t>& active,
                  const Indices& subset, std::size_t num_points) {
    const std::size_t n = cloud.size();
    Indices order;
    order.reserve(num_points);
    if (subset.empty()) {
        for (std::size_t i = 0; i < n; ++i) {
            if (active[i] != 0) order.push_back(static_cast<Index>(i));
        }
    } else {
        for (Index i : subset) {
            if (active[i] != 0) order.push_back(i);
        }
    }
    // Sorted as 64-bit keys (curvature bits made order-preserving, then the index): no
    // indirection in the comparisons.
    std::vector<std::uint64_t> keys(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) {
        const float c = cloud.curvature[order[k]] + 0.0f;  // -0 sorts as 0
        const std::uint32_t bits = std::bit_cast<std::uint32_t>(c);
        const std::uint32_t key = (bits & 0x80000000u) != 0 ? ~bits : bits | 0x80000000u;
        keys[k] = (std::uint64_t{key} << 32) | order[k];
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());  // a subset may repeat points
    order.resize(keys.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<Index>(keys[k]);
    return order;
}

// The grown parts and the seed each grew from, in seed order.
struct GrownParts {
    std::vector<Indices> parts;
    Indices seeds;
};

// Growth: a part is the set of free points reachable from its seed through neighbours whose
// normal is within the angle of the seed normal (not of the neighbour's normal), so that a part
// cannot drift around a curved surface.
GrownParts GrowParts(const PointCloud& cloud, const std::vector<std::uint8_t>& active,
                     const Indices& order, const RegionGrowingParams& params,
                     Neighborhoods& neighborhoods, std::vector<std::int32_t>& part_of) {
    const double max_angle_rad = double{params.max_angle_deg} * std::numbers::pi / 180.0;
    const auto cos_max = static_cast<float>(std::cos(max_angle_rad));
    GrownParts grown;
    for (Index seed : order) {
        if (part_of[seed] != kNoPart) continue;
        const auto id = static_cast<std::int32_t>(grown.parts.size());
        const Eigen::Vector3f seed_normal = cloud.normals[seed].normalized();
        Indices part{seed};
        part_of[seed] = id;
        for (std::size_t head = 0; head < part.size(); ++head) {
            neighborhoods.Search(part[head]);
            for (Index j : neighborhoods.indices()) {
                if (active[j] == 0 || part_of[j] != kNoPart) continue;
                const Eigen::Vector3f& normal = cloud.normals[j];
                float cosine = normal.dot(seed_normal) / normal.norm();
                if (params.ignore_normal_sign) cosine = std::abs(cosine);
                if (cosine > cos_max) {
                    part_of[j] = id;
                    part.push_back(j);
                }
            }
        }
        grown.parts.push_back(std::move(part));
        grown.seeds.push_back(seed);
    }
    return grown;
}

// Merging, phase 1: a small part joins, as a whole, the large part holding the point nearest to
// any of its points (within the neighbourhood; ties by point index). Rounds repeat so that chains
// of small parts reach a large part; decisions of a round use the state before it. Leaves in
// `pending` the small parts with no large part nearby.
void MergeIntoLargeParts(const std::vector<std::uint8_t>& is_large, Neighborhoods& neighborhoods,
                         std::vector<Indices>& parts, std::vector<std::int32_t>& pending,
                         std::vector<std::int32_t>& part_of, RegionGrowingResult& result) {
    std::vector<std::pair<std::int32_t, std::int32_t>> merges;  // (small part, large part)
    while (!pending.empty()) {
        merges.clear();
        for (std::int32_t s : pending) {
            float best_sq = std::numeric_limits<float>::infinity();
            Index best_point = 0;
            std::int32_t best_part = kNoPart;
            for (Index q : parts[static_cast<std::size_t>(s)]) {
                neighborhoods.Search(q);
                const std::span<const Index> nb = neighborhoods.indices();
                const std::span<const float> sq = neighborhoods.squared_distances();
                for (std::size_t m = 0; m < nb.size(); ++m) {
                    const std::int32_t t = part_of[nb[m]];
                    if (t == kNoPart || is_large[static_cast<std::size_t>(t)] == 0) continue;
                    if (sq[m] < best_sq || (sq[m] == best_sq && nb[m] < best_point)) {
                        best_sq = sq[m];
                        best_point = nb[m];
                        best_part = t;
                    }
                }
            }
            if (best_part != kNoPart) merges.emplace_back(s, best_part);
        }
        if (merges.empty()) break;
        for (const auto& [s, t] : merges) {
            Indices& small = parts[static_cast<std::size_t>(s)];
            for (Index i : small) part_of[i] = t;
            Indices& large = parts[static_cast<std::size_t>(t)];
            large.insert(large.end(), small.begin(), small.end());
            small.clear();
        }
        result.num_merged_parts += merges.size();
        std::erase_if(pending,
                      [&](std::int32_t s) { return parts[static_cast<std::size_t>(s)].empty(); });
    }
}

// Merging, phase 2: the remaining small parts have no large part nearby; group them by distance
// alone. A group keeps the id of its first part, so part order stays seed order.
void GroupSmallParts(const std::vector<std::uint8_t>& is_large,
                     const std::vector<std::int32_t>& pending, Neighborhoods& neighborhoods,
                     std::vector<Indices>& parts, std::vector<std::int32_t>& part_of,
                     RegionGrowingResult& result) {
    detail::DisjointSets groups(parts.size());
    for (std::int32_t s : pending) {
        for (Index q : parts[static_cast<std::size_t>(s)]) {
            neighborhoods.Search(q);
            for (Index j : neighborhoods.indices()) {
                const std::int32_t t = part_of[j];
                if (t != kNoPart && t != s && is_large[static_cast<std::size_t>(t)] == 0) {
                    groups.Unite(static_cast<Index>(s), static_cast<Index>(t));
                }
            }
        }
    }
    for (std::int32_t s : pending) {
        const Index root = groups.Find(static_cast<Index>(s));
        if (root == static_cast<Index>(s)) continue;
        Indices& member = parts[static_cast<std::size_t>(s)];
        for (Index i : member) part_of[i] = static_cast<std::int32_t>(root);
        Indices& group = parts[root];
        group.insert(group.end(), member.begin(), member.end());
        member.clear();
        ++result.num_merged_parts;
    }
}

// With discard_small_parts, the groups still too small lose their points (kNoPart).
void DiscardSmallGroups(const std::vector<std::int32_t>& pending, std::size_t min_size,
                        bool discard_small_parts, std::vector<Indices>& parts,
                        std::vector<std::int32_t>& part_of, RegionGrowingResult& result) {
    for (std::int32_t s : pending) {
        Indices& group = parts[static_cast<std::size_t>(s)];
        if (group.empty() || group.size() >= min_size || !discard_small_parts) continue;
        for (Index i : group) part_of[i] = kNoPart;
        result.num_discarded_points += group.size();
        group.clear();
    }
}

// Compaction: surviving parts in seed order, points ascending; part ids renumbered to match
// (only the segmented points, `points`, have one).
void CompactParts(GrownParts& grown, const Indices& points, RegionGrowingResult& result) {
    std::vector<Indices>& parts = grown.parts;
    const std::size_t num_parts = parts.size();
    std::vector<std::int32_t> new_id(num_parts, kNoPart);
    for (std::size_t p = 0; p < num_parts; ++p) {
        if (parts[p].empty()) continue;
        new_id[p] = static_cast<std::int32_t>(result.parts.size());
        std::sort(parts[p].begin(), parts[p].end());
        result.parts.push_back(std::move(parts[p]));
        result.seeds.push_back(grown.seeds[p]);
    }
    for (Index i : points) {
        std::int32_t& id = result.part_ids[i];
        if (id != kNoPart) id = new_id[static_cast<std::size_t>(id)];
    }
}

}  // namespace

void RegionGrowingParams::Validate() const { CheckParams(*this); }

namespace {

// The growth and merging phases on marked points (`active`, result.num_points of them).
void GrowAndMerge(const PointCloud& cloud, const std::vector<std::uint8_t>& active,
                  const RegionGrowingParams& params, Neighborhoods& neighborhoods,
                  RegionGrowingResult& result) {
    std::vector<std::int32_t>& part_of = result.part_ids;
    const Indices order = SeedOrder(cloud, active, params.subset, result.num_points);
    GrownParts grown = GrowParts(cloud, active, order, params, neighborhoods, part_of);
    result.num_grown_parts = grown.parts.size();

    // Parts below min_part_size join a large neighbour, else each other.
    const std::size_t min_size = params.min_part_size;
    std::vector<std::uint8_t> is_large(grown.parts.size(), 0);
    std::vector<std::int32_t> pending;  // small parts not merged yet, ascending
    for (std::size_t p = 0; p < grown.parts.size(); ++p) {
        if (grown.parts[p].size() >= min_size) {
            is_large[p] = 1;
        } else {
            pending.push_back(static_cast<std::int32_t>(p));
        }
    }
    MergeIntoLargeParts(is_large, neighborhoods, grown.parts, pending, part_of, result);
    GroupSmallParts(is_large, pending, neighborhoods, grown.parts, part_of, result);
    DiscardSmallGroups(pending, min_size, params.discard_small_parts, grown.parts, part_of, result);
    CompactParts(grown, order, result);
}

}  // namespace

namespace {

// What every entry point starts with: the checks, the points to segment marked in `active`, every
// part id kNoPart. False when there is nothing to segment.
bool StartGrowing(const PointCloud& cloud, const RegionGrowingParams& params,
                  std::vector<std::uint8_t>& active, RegionGrowingResult& result) {
    CheckParams(params);
    if (cloud.size() == 0) return false;
    CheckFields(cloud);
    result.num_points = MarkPoints(cloud, params.subset, active);
    result.part_ids.assign(cloud.size(), kNoPart);
    return result.num_points > 0;
}

}  // namespace

RegionGrowingResult RegionGrowing(const PointCloud& cloud, const KdTree& tree,
                                  const RegionGrowingParams& params) {
    RegionGrowingResult result;
    std::vector<std::uint8_t> active;
    if (!StartGrowing(cloud, params, active, result)) return result;
    TreeNeighborhoods neighborhoods(cloud, tree, params);
    GrowAndMerge(cloud, active, params, neighborhoods, result);
    return result;
}

namespace {

// Checks what an organized search needs of the cloud and of `search`.
void CheckOrganized(const PointCloud& organized, const OrganizedSearchParams& search) {
    const std::size_t n = organized.size();
    if (!organized.IsOrganized()) {
        throw InvalidArgument(
            fmt::format("organized region growing needs an organized cloud, got {}x{} for {} "
                        "points",
                        organized.width, organized.height, n));
    }
    if (search.half_window < 1) {
        throw InvalidArgument(
            fmt::format("half_window must be >= 1 [pixels], got {}", search.half_window));
    }
    if (!search.mask.empty() && search.mask.size() != n) {
        throw InvalidArgument(fmt::format("the search mask has {} entries for a cloud of {} points",
                                          search.mask.size(), n));
    }
}

// The neighbours of one point: the window's pixels of the mask within the radius (strictly, as
// the k-d tree path keeps them); with k > 0 the k nearest of them, nearest first, else all of
// them in pixel order (no phase depends on the order: growth takes every neighbour, merging the
// nearest).
void WindowNeighbours(const PointCloud& cloud, Index q, int k, float radius_sq,
                      const OrganizedSearchParams& search, Indices& indices,
                      std::vector<float>& squared_distances) {
    if (k > 0) {
        OrganizedKnnSearch(cloud, q, k, search, indices, squared_distances);
    } else {
        OrganizedRadiusSearch(cloud, q, search, indices, squared_distances);
    }
    std::size_t kept = 0;
    for (std::size_t m = 0; m < indices.size(); ++m) {
        if (!(squared_distances[m] < radius_sq)) continue;
        indices[kept] = indices[m];
        squared_distances[kept++] = squared_distances[m];
    }
    indices.resize(kept);
    squared_distances.resize(kept);
}

// The k nearest window neighbours of many points at once, the same as WindowNeighbours gives one
// by one. The pixels around the points are copied once into three coordinate planes (x, y, z),
// NaN where a pixel is no candidate (masked, not finite or beyond the image), so that a window's
// squared distances come row by row, four at a time in Eigen's packets.
class WindowPlanes {
  public:
    WindowPlanes(const PointCloud& cloud, const Indices& points,
                 const OrganizedSearchParams& search, int num_threads)
        : cloud_(cloud), hw_(search.half_window) {
        // The points' pixel rectangle, grown by the window on each side and on the right to a
        // whole number of 4-column blocks.
        std::ptrdiff_t u_lo = std::numeric_limits<std::ptrdiff_t>::max(), u_hi = -1;
        std::ptrdiff_t v_lo = u_lo, v_hi = -1;
        const auto w = static_cast<std::ptrdiff_t>(cloud.width);
        for (Index i : points) {
            const std::ptrdiff_t u = i % w, v = i / w;
            u_lo = std::min(u_lo, u);
            u_hi = std::max(u_hi, u);
            v_lo = std::min(v_lo, v);
            v_hi = std::max(v_hi, v);
        }
        window_cols_ = static_cast<std::size_t>((2 * hw_ + 1 + 3) / 4 * 4);
        u0_ = u_lo - hw_;
        v0_ = v_lo - hw_;
        cols_ = static_cast<std::size_t>(u_hi - u_lo) + window_cols_;
        const auto rows = static_cast<std::size_t>(v_hi - v_lo + 2 * hw_ + 1);
        const float nan = std::numeric_limits<float>::quiet_NaN();
        x_.assign(cols_ * rows, nan);
        y_.assign(cols_ * rows, nan);
        z_.assign(cols_ * rows, nan);
        const std::uint8_t* mask = search.mask.empty() ? nullptr : search.mask.data();
        const auto h = static_cast<std::ptrdiff_t>(cloud.height);
        ParallelFor(
            rows, num_threads,
            [&](std::size_t r) {
                const std::ptrdiff_t v = v0_ + static_cast<std::ptrdiff_t>(r);
                if (v < 0 || v >= h) return;
                for (std::size_t c = 0; c < cols_; ++c) {
                    const std::ptrdiff_t u = u0_ + static_cast<std::ptrdiff_t>(c);
                    if (u < 0 || u >= w) continue;
                    const auto i = static_cast<std::size_t>(v * w + u);
                    const Eigen::Vector3f& p = cloud.points[i];
                    if ((mask != nullptr && mask[i] == 0) || !p.allFinite()) continue;
                    x_[r * cols_ + c] = p.x();
                    y_[r * cols_ + c] = p.y();
                    z_[r * cols_ + c] = p.z();
                }
            },
            16);
        // The window's positions by increasing pixel distance from the centre, as plane offsets
        // (into a window's distances) and image offsets.
        std::vector<std::tuple<int, std::size_t, std::ptrdiff_t>> ring;
        for (int dv = -hw_; dv <= hw_; ++dv) {
            for (int du = -hw_; du <= hw_; ++du) {
                ring.emplace_back(du * du + dv * dv,
                                  static_cast<std::size_t>(dv + hw_) * window_cols_ +
                                      static_cast<std::size_t>(du + hw_),
                                  std::ptrdiff_t{dv} * w + du);
            }
        }
        std::stable_sort(ring.begin(), ring.end(), [](const auto& a, const auto& b) {
            return std::get<0>(a) < std::get<0>(b);
        });
        for (const auto& [d, slot, offset] : ring) {
            ring_slot_.push_back(slot);
            ring_offset_.push_back(offset);
        }
    }

    /// The up to k nearest candidates of `center` strictly within radius_sq, nearest first
    /// (ties by index), as packed keys in keys[0, k) (`keys` has room for k + 1); their number.
    /// `dist` and `listed` are scratch buffers of the calling thread.
    std::size_t Nearest(Index center, std::size_t k, float radius_sq, std::vector<float>& dist,
                        std::vector<std::int32_t>& listed, std::uint64_t* keys) const {
        const auto w = static_cast<std::ptrdiff_t>(cloud_.width);
        const std::ptrdiff_t u = center % w, v = center / w;
        const std::size_t base = static_cast<std::size_t>(v - hw_ - v0_) * cols_ +
                                 static_cast<std::size_t>(u - hw_ - u0_);
        // The centre itself may lie outside the mask; it only needs finite coordinates.
        const Eigen::Vector3f& centre = cloud_.points[center];
        if (!centre.allFinite()) return 0;
        const float cx = centre.x(), cy = centre.y(), cz = centre.z();
        const std::size_t window_rows = static_cast<std::size_t>(2 * hw_ + 1);
        dist.resize(window_rows * window_cols_);
        using Block = Eigen::Array4f;
        for (std::size_t r = 0; r < window_rows; ++r) {
            const std::size_t row = base + r * cols_;
            for (std::size_t c = 0; c < window_cols_; c += 4) {
                const Block dx = Eigen::Map<const Block>(x_.data() + row + c) - cx;
                const Block dy = Eigen::Map<const Block>(y_.data() + row + c) - cy;
                const Block dz = Eigen::Map<const Block>(z_.data() + row + c) - cz;
                // Summed as Eigen's squaredNorm of a 3-vector sums, so the distances are those
                // of the point-by-point search to the last bit.
                Eigen::Map<Block>(dist.data() + r * window_cols_ + c) =
                    dx.square() + (dy.square() + dz.square());
            }
        }
        listed.resize(2 * ring_slot_.size());
        return SelectNearest(dist.data(), center, k, radius_sq, listed.data(), keys);
    }

  private:
    // The k nearest of the window's squared distances `dist` (nearest first, ties by index) as
    // packed keys in keys[0, k); their number. `listed` has room for two windows, `keys` for
    // k + 1 keys.
    [[gnu::noinline]] std::size_t SelectNearest(const float* dist, Index center, std::size_t k,
                                                float radius_sq, std::int32_t* listed,
                                                std::uint64_t* keys) const {
        const std::size_t* slot = ring_slot_.data();
        const std::size_t ring = ring_slot_.size();
        // The first k candidates in ring order bound the k-th nearest distance from above; only
        // candidates within that bound are ranked.
        float bound = -1.0f;
        std::size_t found = 0;
        for (std::size_t q = 0; q < ring && found < k; ++q) {
            const float d2 = dist[slot[q]];
            const bool candidate = d2 < radius_sq;  // NaN: no candidate
            found += static_cast<std::size_t>(candidate);
            bound = std::max(bound, candidate ? d2 : -1.0f);
        }
        if (found < k) bound = radius_sq;
        // The candidates within the bound, listed without a branch per pixel (whether a pixel
        // passes is hard to predict) as their distances' bit patterns (which order like the
        // distances) and their pixels.
        std::int32_t* bits = listed;
        std::int32_t* pixel = listed + ring;
        std::size_t n = 0;
        for (std::size_t q = 0; q < ring; ++q) {
            const float d2 = dist[slot[q]];
            bits[n] = std::bit_cast<std::int32_t>(d2);
            pixel[n] =
                static_cast<std::int32_t>(static_cast<std::ptrdiff_t>(center) + ring_offset_[q]);
            n += static_cast<std::size_t>(static_cast<int>(d2 < radius_sq) &
                                          static_cast<int>(d2 <= bound));
        }
        // Each candidate's rank among them by distance, then pixel (the keys' order; no two are
        // equal) is its place; ranks from k on go to the spare slot keys[k].
        for (std::size_t i = 0; i < n; ++i) {
            const std::int32_t b = bits[i], p = pixel[i];
            std::int32_t rank = 0;
            for (std::size_t j = 0; j < n; ++j) {
                rank += static_cast<std::int32_t>(bits[j] < b) |
                        (static_cast<std::int32_t>(bits[j] == b) &
                         static_cast<std::int32_t>(pixel[j] < p));
            }
            keys[std::min(static_cast<std::size_t>(rank), k)] =
                detail::PackNeighbour(std::bit_cast<float>(b), static_cast<Index>(p));
        }
        return std::min(n, k);
    }

    const PointCloud& cloud_;
    int hw_;
    std::ptrdiff_t u0_ = 0, v0_ = 0;
    std::size_t cols_ = 0, window_cols_ = 0;
    std::vector<float> x_, y_, z_;
    std::vector<std::size_t> ring_slot_;
    std::vector<std::ptrdiff_t> ring_offset_;
};

}  // namespace

NeighbourTable OrganizedNeighbourTable(const PointCloud& organized, const Indices& points,
                                       const RegionGrowingParams& params,
                                       const OrganizedSearchParams& search, int num_threads) {
    CheckParams(params);
    CheckOrganized(organized, search);
    NeighbourTable table;
    const std::size_t n = organized.size();
    const auto window = static_cast<std::size_t>(2 * search.half_window + 1);
    table.stride = window * window;
    if (params.k > 0) table.stride = std::min(table.stride, static_cast<std::size_t>(params.k));
    if (table.stride > 0xffff) {
        throw InvalidArgument(
            fmt::format("a neighbour table row holds at most 65535 entries, the "
                        "window of {} pixels more",
                        search.half_window));
    }
    if (n > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
        // The k-nearest selection ranks pixels as 31-bit numbers.
        throw InvalidArgument(
            fmt::format("a neighbour table is for frames of at most 2^31 - 1 pixels, got {}", n));
    }
    table.row_of.assign(n, NeighbourTable::kNoRow);
    for (std::size_t r = 0; r < points.size(); ++r) {
        if (points[r] >= n) {
            throw InvalidArgument(
                fmt::format("index {} is out of range for a cloud of {} points", points[r], n));
        }
        table.row_of[points[r]] = static_cast<std::uint32_t>(r);
    }
    table.count.assign(points.size(), 0);
    table.neighbours.resize(points.size() * table.stride);
    table.squared_distances.resize(points.size() * table.stride);
    OrganizedSearchParams s = search;
    s.radius = params.radius;
    const float radius_sq = params.radius * params.radius;
    if (params.k > 0 && !points.empty()) {
        const WindowPlanes planes(organized, points, search, num_threads);
        const auto k = static_cast<std::size_t>(params.k);
        ParallelForChunks(
            points.size(), num_threads,
            [&](std::size_t begin, std::size_t end) {
                std::vector<float> dist;
                std::vector<std::int32_t> listed;
                std::vector<std::uint64_t> keys(k + 1);
                for (std::size_t r = begin; r < end; ++r) {
                    const std::size_t m =
                        planes.Nearest(points[r], k, radius_sq, dist, listed, keys.data());
                    for (std::size_t j = 0; j < m; ++j) {
                        table.neighbours[r * table.stride + j] = detail::PackedIndex(keys[j]);
                        table.squared_distances[r * table.stride + j] =
                            detail::PackedSquaredDistance(keys[j]);
                    }
                    table.count[r] = static_cast<std::uint16_t>(m);
                }
            },
            1024);
        return table;
    }
    ParallelForChunks(
        points.size(), num_threads,
        [&](std::size_t begin, std::size_t end) {
            Indices nb;
            std::vector<float> d2;
            for (std::size_t r = begin; r < end; ++r) {
                WindowNeighbours(organized, points[r], params.k, radius_sq, s, nb, d2);
                const std::size_t m = std::min(nb.size(), table.stride);
                std::copy_n(nb.begin(), m, table.neighbours.begin() + r * table.stride);
                std::copy_n(d2.begin(), m, table.squared_distances.begin() + r * table.stride);
                table.count[r] = static_cast<std::uint16_t>(m);
            }
        },
        1024);
    return table;
}

RegionGrowingResult RegionGrowing(const PointCloud& cloud, const NeighbourTable& table,
                                  const RegionGrowingParams& params) {
    RegionGrowingResult result;
    std::vector<std::uint8_t> active;
    if (!StartGrowing(cloud, params, active, result)) return result;
    const std::size_t n = cloud.size();
    if (table.row_of.size() != n) {
        throw InvalidArgument(fmt::format("the neighbour table is for a cloud of {} points, not {}",
                                          table.row_of.size(), n));
    }
    auto check_row = [&](std::size_t i) {
        if (active[i] != 0 && table.row_of[i] == NeighbourTable::kNoRow) {
            throw InvalidArgument(fmt::format(
                "point {} is to be segmented but the neighbour table has no row for it", i));
        }
    };
    if (params.subset.empty()) {
        for (std::size_t i = 0; i < n; ++i) check_row(i);
    } else {
        for (Index i : params.subset) check_row(i);  // only they can be marked
    }
    TableNeighborhoods neighborhoods(table);
    GrowAndMerge(cloud, active, params, neighborhoods, result);
    return result;
}

RegionGrowingResult RegionGrowingOrganized(const PointCloud& organized,
                                           const RegionGrowingParams& params,
                                           const OrganizedSearchParams& search) {
    CheckParams(params);
    if (organized.size() == 0) return {};
    CheckOrganized(organized, search);
    CheckFields(organized);
    std::vector<std::uint8_t> active;
    MarkPoints(organized, params.subset, active);
    Indices points;
    for (std::size_t i = 0; i < organized.size(); ++i) {
        if (active[i] == 0) continue;
        if (!search.mask.empty() && search.mask[i] == 0) {
            throw InvalidArgument(
                fmt::format("point {} is to be segmented but the search mask leaves it out", i));
        }
        points.push_back(static_cast<Index>(i));
    }
    return RegionGrowing(organized, OrganizedNeighbourTable(organized, points, params, search),
                         params);
}

}  // namespace multicue
