#include "multicue/search/voxel_hash_map.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"

namespace multicue {
namespace {

// Work is split into fixed blocks of points (never into per-thread shares), so every partial
// result, and therefore the output, is the same for any thread count.
constexpr std::size_t kBlock = 16384;
// Radix digits of at most 12 bits: 4096 counters (16 KiB) per block stay in L1, and the 24-bit
// keys of a 640x480 frame at 5 mm sort in two passes.
constexpr unsigned kMaxDigitBits = 12;
constexpr double kInt32Range = 2147483648.0;  // 2^31

std::size_t NumBlocks(std::size_t n) { return (n + kBlock - 1) / kBlock; }

float InverseLeaf(float leaf_size) {
    if (!(leaf_size > 0.0f) || !std::isfinite(leaf_size)) {
        throw InvalidArgument(fmt::format("leaf_size must be > 0, got {}", leaf_size));
    }
    const float inv = 1.0f / leaf_size;
    if (!std::isfinite(inv)) {
        throw InvalidArgument(
            fmt::format("leaf_size {} is too small (1/leaf_size overflows)", leaf_size));
    }
    return inv;
}

// floor() for |s| < 2^62: truncate, then step down for negative non-integers. Same result as
// std::floor, which without SSE4.1 is a library call and dominated the key computation.
inline std::int64_t FloorToInt(float s) {
    const auto t = static_cast<std::int64_t>(s);
    return t - static_cast<std::int64_t>(static_cast<float>(t) > s);
}

// True when x, y and z are all finite: x - x is 0 for finite x and NaN for infinity or NaN. One
// comparison instead of three classifications in the two loops over every point.
inline bool AllFinite(float x, float y, float z) { return (x - x) + (y - y) + (z - z) == 0.0f; }

// A scaled coordinate that fits a 32-bit voxel coordinate after floor().
bool InInt32Range(float scaled) {
    const double f = std::floor(double{scaled});
    return f >= -kInt32Range && f < kInt32Range;
}

// Element types for the radix sort. With at most 2^32 voxel keys a (key, index) pair packs into
// one 64-bit word, halving the memory traffic of every pass.
struct PackedPair {
    using T = std::uint64_t;
    static T Make(std::uint64_t key, Index i) { return (key << 32) | i; }
    static std::uint64_t Key(T e) { return e >> 32; }
    static Index Idx(T e) { return static_cast<Index>(e); }
};
struct WidePair {
    struct T {
        std::uint64_t key;
        Index idx;
    };
    static T Make(std::uint64_t key, Index i) { return {key, i}; }
    static std::uint64_t Key(const T& e) { return e.key; }
    static Index Idx(const T& e) { return e.idx; }
};

// Bounding grid of a cloud's finite points.
struct Grid {
    float inv_leaf = 0.0f;
    std::array<std::int64_t, 3> lo{};
    std::array<std::uint64_t, 3> dims{};
    unsigned key_bits = 0;  // bits of the largest key
    std::size_t finite = 0;
    std::vector<std::size_t> block_offsets;  // first output slot of each block's finite points
};

Grid ComputeGrid(const PointCloud& cloud, float leaf_size, int num_threads) {
    Grid grid;
    grid.inv_leaf = InverseLeaf(leaf_size);
    const std::size_t n = cloud.size();
    const std::size_t nb = NumBlocks(n);
    struct Bounds {
        Eigen::Array3f lo, hi;
        std::size_t count;
    };
    std::vector<Bounds> bounds(nb);
    const Eigen::Vector3f* pts = cloud.points.data();
    ParallelFor(
        nb, num_threads,
        [&](std::size_t b) {
            constexpr float kInf = std::numeric_limits<float>::infinity();
            float lx = kInf, ly = kInf, lz = kInf, hx = -kInf, hy = -kInf, hz = -kInf;
            std::size_t count = 0;
            const std::size_t end = std::min(n, (b + 1) * kBlock);
            for (std::size_t i = b * kBlock; i < end; ++i) {
                const float x = pts[i].x(), y = pts[i].y(), z = pts[i].z();
                // Branch-free: invalid pixels come in runs of any length.
                const bool ok = AllFinite(x, y, z);
                lx = ok ? std::min(lx, x) : lx;
                ly = ok ? std::min(ly, y) : ly;
                lz = ok ? std::min(lz, z) : lz;
                hx = ok ? std::max(hx, x) : hx;
                hy = ok ? std::max(hy, y) : hy;
                hz = ok ? std::max(hz, z) : hz;
                count += ok;
            }
            const Eigen::Array3f lo(lx, ly, lz), hi(hx, hy, hz);
            bounds[b] = {lo, hi, count};
        },
        1);
    Eigen::Array3f lo = Eigen::Array3f::Constant(std::numeric_limits<float>::infinity());
    Eigen::Array3f hi = -lo;
    grid.block_offsets.resize(nb);
    for (std::size_t b = 0; b < nb; ++b) {
        grid.block_offsets[b] = grid.finite;
        grid.finite += bounds[b].count;
        lo = lo.min(bounds[b].lo);
        hi = hi.max(bounds[b].hi);
    }
    if (grid.finite == 0) return grid;

    const Eigen::Array3f lo_scaled = lo * grid.inv_leaf, hi_scaled = hi * grid.inv_leaf;
    for (int a = 0; a < 3; ++a) {
        if (!InInt32Range(lo_scaled[a]) || !InInt32Range(hi_scaled[a])) {
            const double largest = std::max(std::abs(double{lo[a]}), std::abs(double{hi[a]}));
            throw InvalidArgument(fmt::format(
                "leaf_size {} is too small for coordinates up to {:.6g}: voxel coordinates leave "
                "the 32-bit range; use leaf_size >= {:.3g}",
                leaf_size, largest, largest / kInt32Range * 1.01));
        }
        grid.lo[a] = static_cast<std::int64_t>(std::floor(lo_scaled[a]));
        grid.dims[a] = static_cast<std::uint64_t>(
            static_cast<std::int64_t>(std::floor(hi_scaled[a])) - grid.lo[a] + 1);
    }
    std::uint64_t xy = 0, total = 0;
    if (__builtin_mul_overflow(grid.dims[0], grid.dims[1], &xy) ||
        __builtin_mul_overflow(xy, grid.dims[2], &total)) {
        const double voxels = static_cast<double>(grid.dims[0]) *
                              static_cast<double>(grid.dims[1]) * static_cast<double>(grid.dims[2]);
        const double min_leaf = leaf_size * std::cbrt(voxels / 18446744073709551616.0) * 1.01;
        throw InvalidArgument(fmt::format(
            "leaf_size {} is too small for a cloud spanning {:.6g} x {:.6g} x {:.6g}: the voxel "
            "grid would have {:.3g} voxels, more than the 2^64 keys of the voxel index; use "
            "leaf_size >= {:.3g}",
            leaf_size, hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], voxels, min_leaf));
    }
    grid.key_bits = total <= 1 ? 0u : static_cast<unsigned>(std::bit_width(total - 1));
    return grid;
}

// Digits of the LSD radix sort for keys of `key_bits` bits: as few passes as possible, digits of
// equal width.
struct Digits {
    unsigned passes = 0;
    unsigned bits = 0;
    std::size_t buckets = 1;
    std::uint64_t mask = 0;
};

Digits DigitsFor(unsigned key_bits) {
    Digits d;
    if (key_bits == 0) return d;
    d.passes = (key_bits + kMaxDigitBits - 1) / kMaxDigitBits;
    d.bits = (key_bits + d.passes - 1) / d.passes;
    d.buckets = std::size_t{1} << d.bits;
    d.mask = d.buckets - 1;
    return d;
}

// Turns per-block digit counts into per-block write positions: block b writes digit d after all
// smaller digits and after blocks < b with digit d, which keeps the sort stable. Both loops run
// along the rows of `hist` (one row of `buckets` counters per block).
void CountsToPositions(std::vector<std::uint32_t>& hist, std::size_t buckets,
                       std::vector<std::uint32_t>& start) {
    const std::size_t nb = hist.size() / buckets;
    start.assign(buckets, 0u);
    for (std::size_t b = 0; b < nb; ++b) {
        const std::uint32_t* h = hist.data() + b * buckets;
        for (std::size_t d = 0; d < buckets; ++d) start[d] += h[d];
    }
    std::uint32_t sum = 0;
    for (std::size_t d = 0; d < buckets; ++d) {
        const std::uint32_t c = start[d];
        start[d] = sum;
        sum += c;
    }
    for (std::size_t b = 0; b < nb; ++b) {
        std::uint32_t* h = hist.data() + b * buckets;
        for (std::size_t d = 0; d < buckets; ++d) {
            const std::uint32_t c = h[d];
            h[d] = start[d];
            start[d] += c;
        }
    }
}

// Calls f(i, 0) for i in [begin, mid) and f(i, 1) for i in [mid, end), alternating between the
// two halves: each half counts into its own histogram row, so the two chains of counter updates
// overlap instead of waiting on each other when consecutive keys share a digit (as neighbouring
// pixels do). Requires mid - begin == end - mid or one more.
template <typename F>
inline void TwoLanes(std::size_t begin, std::size_t mid, std::size_t end, F&& f) {
    const std::size_t second = end - mid;
    for (std::size_t i = 0; i < second; ++i) {
        f(begin + i, 0);
        f(mid + i, 1);
    }
    if (mid - begin > second) f(begin + second, 0);
}

// Stable LSD radix sort of data[0, m) by key. Task t sorts lanes 2t and 2t+1, lane l being
// data[lanes[l], lanes[l+1]) with histogram row l; `hist` holds the first digit's counts on entry.
// `tmp` is scratch of the same size as data; on return `data` points to the sorted buffer.
template <typename Traits>
void RadixSort(typename Traits::T*& data, typename Traits::T*& tmp,
               const std::vector<std::size_t>& lanes, const Digits& digits,
               std::vector<std::uint32_t>& hist, int num_threads) {
    const std::size_t tasks = (lanes.size() - 1) / 2;
    const std::size_t buckets = digits.buckets;
    const std::uint64_t mask = digits.mask;
    std::vector<std::uint32_t> start;
    for (unsigned pass = 0; pass < digits.passes; ++pass) {
        const unsigned shift = pass * digits.bits;
        if (pass > 0) {
            ParallelFor(
                tasks, num_threads,
                [&, shift, mask, in = data](std::size_t t) {
                    std::uint32_t* h[2] = {hist.data() + 2 * t * buckets,
                                           hist.data() + (2 * t + 1) * buckets};
                    std::fill(h[0], h[0] + 2 * buckets, 0u);
                    TwoLanes(lanes[2 * t], lanes[2 * t + 1], lanes[2 * t + 2],
                             [&](std::size_t i, int l) {
                                 ++h[l][(Traits::Key(in[i]) >> shift) & mask];
                             });
                },
                1);
        }
        CountsToPositions(hist, buckets, start);
        ParallelFor(
            tasks, num_threads,
            [&, shift, mask, in = data, out = tmp](std::size_t t) {
                std::uint32_t* h[2] = {hist.data() + 2 * t * buckets,
                                       hist.data() + (2 * t + 1) * buckets};
                TwoLanes(lanes[2 * t], lanes[2 * t + 1], lanes[2 * t + 2],
                         [&](std::size_t i, int l) {
                             out[h[l][(Traits::Key(in[i]) >> shift) & mask]++] = in[i];
                         });
            },
            1);
        std::swap(data, tmp);
    }
}

template <typename Traits>
void Partition(const PointCloud& cloud, const Grid& grid, int num_threads, VoxelPartition& out) {
    using T = typename Traits::T;
    const std::size_t n = cloud.size();
    const std::size_t m = grid.finite;
    auto buffer_a = std::make_unique_for_overwrite<T[]>(m);
    auto buffer_b = std::make_unique_for_overwrite<T[]>(m);
    T* data = buffer_a.get();
    T* tmp = buffer_b.get();

    // Keys of the finite points in point order: block b of points fills lanes 2b and 2b+1 (its
    // share of data, halved) and counts the first radix digit of its keys on the way.
    const std::size_t nb = grid.block_offsets.size();
    std::vector<std::size_t> lanes(2 * nb + 1);
    for (std::size_t b = 0; b < nb; ++b) {
        const std::size_t begin = grid.block_offsets[b];
        const std::size_t end = b + 1 < nb ? grid.block_offsets[b + 1] : m;
        lanes[2 * b] = begin;
        lanes[2 * b + 1] = begin + (end - begin + 1) / 2;
    }
    lanes[2 * nb] = m;
    const Digits digits = DigitsFor(grid.key_bits);
    std::vector<std::uint32_t> hist(2 * nb * digits.buckets);
    const Eigen::Vector3f* pts = cloud.points.data();
    const std::uint64_t nx = grid.dims[0], nz = grid.dims[2];
    ParallelFor(
        nb, num_threads,
        [&, mask = digits.mask](std::size_t b) {
            std::uint32_t* h0 = hist.data() + 2 * b * digits.buckets;
            std::uint32_t* h1 = h0 + digits.buckets;
            std::size_t o = lanes[2 * b];
            const std::size_t mid = lanes[2 * b + 1];
            const std::size_t end = std::min(n, (b + 1) * kBlock);
            for (std::size_t i = b * kBlock; i < end; ++i) {
                const float px = pts[i].x(), py = pts[i].y(), pz = pts[i].z();
                if (!AllFinite(px, py, pz)) continue;
                const std::int64_t x = FloorToInt(px * grid.inv_leaf);
                const std::int64_t y = FloorToInt(py * grid.inv_leaf);
                const std::int64_t z = FloorToInt(pz * grid.inv_leaf);
                const std::uint64_t key = (static_cast<std::uint64_t>(y - grid.lo[1]) * nx +
                                           static_cast<std::uint64_t>(x - grid.lo[0])) *
                                              nz +
                                          static_cast<std::uint64_t>(z - grid.lo[2]);
                ++(o < mid ? h0 : h1)[key & mask];
                data[o++] = Traits::Make(key, static_cast<Index>(i));
            }
        },
        1);

    RadixSort<Traits>(data, tmp, lanes, digits, hist, num_threads);

    // Runs of equal keys are the voxels: count the run starts per block, then write them.
    std::vector<std::size_t> blocks(nb + 1);
    for (std::size_t b = 0; b <= nb; ++b) blocks[b] = lanes[2 * b];
    std::vector<std::size_t> first_voxel(nb + 1, 0);
    ParallelFor(
        nb, num_threads,
        [&](std::size_t b) {
            std::size_t starts = 0;
            for (std::size_t i = blocks[b]; i < blocks[b + 1]; ++i) {
                starts += i == 0 || Traits::Key(data[i]) != Traits::Key(data[i - 1]);
            }
            first_voxel[b + 1] = starts;
        },
        1);
    for (std::size_t b = 0; b < nb; ++b) first_voxel[b + 1] += first_voxel[b];
    const std::size_t num_voxels = first_voxel[nb];
    out.keys.resize(num_voxels);
    out.offsets.resize(num_voxels + 1);
    out.indices.resize(m);
    ParallelFor(
        nb, num_threads,
        [&](std::size_t b) {
            std::size_t v = first_voxel[b];
            for (std::size_t i = blocks[b]; i < blocks[b + 1]; ++i) {
                const std::uint64_t key = Traits::Key(data[i]);
                if (i == 0 || key != Traits::Key(data[i - 1])) {
                    out.keys[v] = key;
                    out.offsets[v] = static_cast<std::uint32_t>(i);
                    ++v;
                }
                out.indices[i] = Traits::Idx(data[i]);
            }
        },
        1);
    out.offsets[num_voxels] = static_cast<std::uint32_t>(m);
}

std::uint64_t HashSlot(std::uint64_t key, int shift) {
    return (key * 0x9E3779B97F4A7C15ull) >> shift;  // Fibonacci hashing
}

}  // namespace

Eigen::Vector3i VoxelPartition::Coordinates(std::size_t v) const {
    const std::uint64_t key = keys[v];
    const std::uint64_t z = key % dims[2];
    const std::uint64_t x = (key / dims[2]) % dims[0];
    const std::uint64_t y = key / dims[2] / dims[0];
    return {static_cast<int>(origin.x() + static_cast<std::int64_t>(x)),
            static_cast<int>(origin.y() + static_cast<std::int64_t>(y)),
            static_cast<int>(origin.z() + static_cast<std::int64_t>(z))};
}

VoxelPartition PartitionByVoxel(const PointCloud& cloud, const VoxelHashMapParams& params) {
    if (cloud.size() > std::numeric_limits<Index>::max()) {
        throw InvalidArgument(
            fmt::format("a cloud of {} points exceeds the 32-bit point index", cloud.size()));
    }
    ResolveThreadCount(params.num_threads);  // reject negative counts even for tiny clouds
    const Grid grid = ComputeGrid(cloud, params.leaf_size, params.num_threads);
    VoxelPartition out;
    out.leaf_size = params.leaf_size;
    if (grid.finite == 0) {
        out.offsets.assign(1, 0);
        return out;
    }
    out.origin = {static_cast<int>(grid.lo[0]), static_cast<int>(grid.lo[1]),
                  static_cast<int>(grid.lo[2])};
    out.dims = grid.dims;
    if (grid.key_bits <= 32) {
        Partition<PackedPair>(cloud, grid, params.num_threads, out);
    } else {
        Partition<WidePair>(cloud, grid, params.num_threads, out);
    }
    return out;
}

Eigen::Vector3i VoxelCoordinates(const Eigen::Vector3f& point, float leaf_size) {
    const float inv = InverseLeaf(leaf_size);
    if (!point.allFinite()) {
        throw InvalidArgument(
            fmt::format("point ({}, {}, {}) is not finite", point.x(), point.y(), point.z()));
    }
    Eigen::Vector3i c;
    for (int a = 0; a < 3; ++a) {
        const float s = point[a] * inv;
        if (!InInt32Range(s)) {
            throw InvalidArgument(
                fmt::format("coordinate {} at leaf_size {} leaves the 32-bit voxel range", point[a],
                            leaf_size));
        }
        c[a] = static_cast<int>(std::floor(s));
    }
    return c;
}

VoxelHashMap::VoxelHashMap(const PointCloud& cloud, const VoxelHashMapParams& params)
    : partition_(PartitionByVoxel(cloud, params)) {
    const std::size_t v = partition_.num_voxels();
    // Power-of-two capacity with load factor in (1/4, 1/2]: short linear probes.
    const std::size_t capacity = std::max<std::size_t>(16, std::bit_ceil(2 * v));
    shift_ = 64 - std::countr_zero(capacity);
    table_.assign(capacity, Slot{0, kNoVoxel});
    const std::size_t mask = capacity - 1;
    for (std::size_t i = 0; i < v; ++i) {
        const std::uint64_t key = partition_.keys[i];
        std::size_t s = HashSlot(key, shift_);
        while (table_[s].voxel != kNoVoxel) s = (s + 1) & mask;
        table_[s] = {key, static_cast<VoxelId>(i)};
    }
}

bool VoxelHashMap::KeyOf(const std::array<std::int64_t, 3>& coordinates, std::uint64_t& key) const {
    if (empty()) return false;
    std::array<std::uint64_t, 3> rel{};
    for (std::size_t a = 0; a < 3; ++a) {
        const std::int64_t d = coordinates[a] - partition_.origin[static_cast<int>(a)];
        if (d < 0 || static_cast<std::uint64_t>(d) >= partition_.dims[a]) return false;
        rel[a] = static_cast<std::uint64_t>(d);
    }
    key = (rel[1] * partition_.dims[0] + rel[0]) * partition_.dims[2] + rel[2];
    return true;
}

VoxelHashMap::VoxelId VoxelHashMap::Lookup(std::uint64_t key) const {
    const std::size_t mask = table_.size() - 1;
    for (std::size_t s = HashSlot(key, shift_);; s = (s + 1) & mask) {
        const Slot& slot = table_[s];
        if (slot.voxel == kNoVoxel) return kNoVoxel;
        if (slot.key == key) return slot.voxel;
    }
}

VoxelHashMap::VoxelId VoxelHashMap::Find(const Eigen::Vector3i& coordinates) const {
    std::uint64_t key = 0;
    return KeyOf({coordinates.x(), coordinates.y(), coordinates.z()}, key) ? Lookup(key) : kNoVoxel;
}

VoxelHashMap::VoxelId VoxelHashMap::FindVoxelOf(const Eigen::Vector3f& point) const {
    if (empty() || !point.allFinite()) return kNoVoxel;
    const float inv = 1.0f / partition_.leaf_size;
    Eigen::Vector3i c;
    for (int a = 0; a < 3; ++a) {
        const float s = point[a] * inv;
        if (!InInt32Range(s)) return kNoVoxel;
        c[a] = static_cast<int>(std::floor(s));
    }
    return Find(c);
}

std::size_t VoxelHashMap::Neighbors(const Eigen::Vector3i& coordinates, bool include_center,
                                    std::vector<VoxelId>& voxels) const {
    voxels.clear();
    // Lexicographic (dy, dx, dz) order is ascending key order, hence ascending VoxelId.
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            for (int dz = -1; dz <= 1; ++dz) {
                if (!include_center && dx == 0 && dy == 0 && dz == 0) continue;
                std::uint64_t key = 0;
                if (!KeyOf({std::int64_t{coordinates.x()} + dx, std::int64_t{coordinates.y()} + dy,
                            std::int64_t{coordinates.z()} + dz},
                           key)) {
                    continue;
                }
                const VoxelId v = Lookup(key);
                if (v != kNoVoxel) voxels.push_back(v);
            }
        }
    }
    return voxels.size();
}

}  // namespace multicue
