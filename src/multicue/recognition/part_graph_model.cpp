#include "multicue/recognition/part_graph_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <unordered_map>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/features/grsd.hpp"
#include "multicue/ml/serialization.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

namespace {

constexpr std::string_view kMagic = "MCPARTGR";
using Row = Eigen::Matrix<float, 1, kPartDescriptorSize>;

float GrsdSum(const float* d) {
    float s = 0.0f;
    for (int j = 0; j < kPartGrsdSize; ++j) s += d[j];
    return s;
}

// Splitmix64: a portable stream for the training sample.
struct SplitMix {
    std::uint64_t state;
    std::uint64_t Next() {
        std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    std::uint64_t Below(std::uint64_t n) { return Next() % n; }
};

void ValidateDescriptorParams(const PartDescriptorParams& p) {
    auto ok = [](float w) { return w >= 0.0f && std::isfinite(w); };
    if (!ok(p.size_weight)) throw InvalidArgument("size_weight must be >= 0 and finite");
    for (float w : p.extent_weights) {
        if (!ok(w)) throw InvalidArgument("extent_weights must be >= 0 and finite");
    }
    if (!ok(p.grsd_weight)) throw InvalidArgument("grsd_weight must be >= 0 and finite");
    if (!ok(p.elevation_weight)) {
        throw InvalidArgument("elevation_weight must be >= 0 and finite");
    }
    if (!ok(p.rsd_weight)) throw InvalidArgument("rsd_weight must be >= 0 and finite");
    const float q = p.voxels.rsd.angle_quantile;
    if (!(q > 0.0f && q <= 1.0f)) throw InvalidArgument("RSD angle_quantile must be in (0, 1]");
}

// Unit-sum, square-rooted counts times `weight` (all zero when nothing was counted).
void MapCounts(const float* in, int n, float weight, float* out) {
    double sum = 0.0;
    for (int j = 0; j < n; ++j) sum += std::max(in[j], 0.0f);
    const double inv = sum > 0.0 ? 1.0 / sum : 0.0;
    for (int j = 0; j < n; ++j) {
        out[j] = weight * static_cast<float>(std::sqrt(std::max(in[j], 0.0f) * inv));
    }
}

// The union of the parts' finite points as a cloud of its own (with normals), each point's part,
// and each part's points in it: the voxel RSD then sees the parts' neighbours across borders.
struct PartCloud {
    PointCloud sub;
    std::vector<std::int32_t> owner_part;
    std::vector<std::vector<Index>> local;
};

PartCloud GatherParts(const PointCloud& cloud, const std::vector<Indices>& parts,
                      std::size_t total) {
    PartCloud pc;
    PointCloud& sub = pc.sub;
    pc.local.resize(parts.size());
    sub.points.reserve(total);
    sub.normals.reserve(total);
    for (std::size_t p = 0; p < parts.size(); ++p) {
        for (Index i : parts[p]) {
            if (!cloud.points[i].allFinite()) continue;
            pc.local[p].push_back(static_cast<Index>(sub.points.size()));
            sub.points.push_back(cloud.points[i]);
            sub.normals.push_back(cloud.normals[i]);
            pc.owner_part.push_back(static_cast<std::int32_t>(p));
        }
    }
    sub.width = static_cast<std::uint32_t>(sub.points.size());
    sub.height = 1;
    return pc;
}

// Rows of a right-handed frame whose z axis is up.
Eigen::Matrix3d UpFrame(const Eigen::Vector3f& up) {
    Eigen::Matrix3d frame;
    const Eigen::Vector3d z = up.cast<double>();
    const Eigen::Vector3d helper =
        std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d x = (helper - helper.dot(z) * z).normalized();
    frame.row(0) = x.transpose();
    frame.row(1) = z.cross(x).transpose();
    frame.row(2) = z.transpose();
    return frame;
}

// Per part: the moments about the mean of all points (small numbers, still additive over parts,
// so that a subgraph's descriptor is the sum of its parts'), in the up frame, and the histogram
// of its normals' elevation against up.
void AddMomentsAndElevations(const PartCloud& pc, const Eigen::Vector3f& up, FeatureMatrix& out) {
    const PointCloud& sub = pc.sub;
    const Eigen::Matrix3d frame = UpFrame(up);
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    for (const auto& q : sub.points) origin += q.cast<double>();
    origin /= static_cast<double>(sub.points.size());
    for (std::size_t p = 0; p < pc.local.size(); ++p) {
        double m[kPartMomentSize] = {};
        for (Index i : pc.local[p]) {
            const Eigen::Vector3d q = frame * (sub.points[i].cast<double>() - origin);
            m[0] += 1.0;
            m[1] += q.x();
            m[2] += q.y();
            m[3] += q.z();
            m[4] += q.x() * q.x();
            m[5] += q.x() * q.y();
            m[6] += q.x() * q.z();
            m[7] += q.y() * q.y();
            m[8] += q.y() * q.z();
            m[9] += q.z() * q.z();
        }
        for (int j = 0; j < kPartMomentSize; ++j) {
            out(static_cast<Eigen::Index>(p), kPartMomentOffset + j) = static_cast<float>(m[j]);
        }
        // Elevation of the normals against up.
        for (Index i : pc.local[p]) {
            const Eigen::Vector3f& nrm = sub.normals[i];
            if (!nrm.allFinite() || !(nrm.squaredNorm() > 0.0f)) continue;
            const float e = std::min(std::abs(nrm.normalized().dot(up)), 1.0f);
            const int bin =
                std::min(static_cast<int>(e * kPartElevationSize), kPartElevationSize - 1);
            out(static_cast<Eigen::Index>(p), kPartElevationOffset + bin) += 1.0f;
        }
    }
}

// Curvature counts: every point takes the minimum radius of its voxel (below 3 cm, below 10 cm,
// flatter).
void AddCurvatureCounts(const VoxelRsdResult& voxels, const PartCloud& pc, FeatureMatrix& out) {
    for (std::size_t i = 0; i < pc.sub.points.size(); ++i) {
        const std::uint32_t v = voxels.point_voxel[i];
        if (v == VoxelRsdResult::kNoVoxel) continue;
        const float r = voxels.radii(static_cast<Eigen::Index>(v), 0);
        if (!std::isfinite(r)) continue;
        const int bin = r < 0.03f ? 0 : (r < 0.10f ? 1 : 2);
        out(static_cast<Eigen::Index>(pc.owner_part[i]), kPartRsdOffset + bin) += 1.0f;
    }
}

// The voxels of each part: every voxel goes to the part holding most of its points (ties to the
// lower part), so that no voxel counts twice in a subgraph's GRSD-.
std::vector<std::vector<std::uint32_t>> VoxelsByMajorityOwner(const VoxelRsdResult& voxels,
                                                              const PartCloud& pc) {
    const std::size_t nv = voxels.size();
    std::vector<std::unordered_map<std::int32_t, std::uint32_t>> counts(nv);
    for (std::size_t i = 0; i < pc.sub.points.size(); ++i) {
        const std::uint32_t v = voxels.point_voxel[i];
        if (v == VoxelRsdResult::kNoVoxel) continue;
        ++counts[v][pc.owner_part[i]];
    }
    std::vector<std::vector<std::uint32_t>> owned(pc.local.size());
    for (std::uint32_t v = 0; v < nv; ++v) {
        std::int32_t best = -1;
        std::uint32_t best_count = 0;
        for (const auto& [p, c] : counts[v]) {
            if (c > best_count || (c == best_count && p < best)) {
                best = p;
                best_count = c;
            }
        }
        if (best >= 0) owned[static_cast<std::size_t>(best)].push_back(v);
    }
    return owned;
}

}  // namespace

FeatureMatrix ComputePartDescriptors(const PointCloud& cloud, const std::vector<Indices>& parts,
                                     const PartDescriptorParams& params,
                                     const Eigen::Vector3f& up_in) {
    ValidateDescriptorParams(params);
    if (!up_in.allFinite()) throw InvalidArgument("part descriptors: up must be finite");
    const Eigen::Vector3f up =
        up_in.norm() > 1e-6f ? Eigen::Vector3f(up_in.normalized()) : Eigen::Vector3f(0, -1, 0);
    FeatureMatrix out =
        FeatureMatrix::Zero(static_cast<Eigen::Index>(parts.size()), kPartDescriptorSize);
    for (std::size_t p = 0; p < parts.size(); ++p) {
        for (Index i : parts[p]) {
            if (i >= cloud.size()) throw InvalidArgument("part descriptors: index out of range");
        }
    }
    std::size_t total = 0;
    for (const auto& part : parts) total += part.size();
    if (total == 0) return out;
    if (!cloud.HasNormals() || cloud.normals.size() != cloud.size()) {
        throw DataError("part descriptors need one normal per point");
    }
    const PartCloud pc = GatherParts(cloud, parts, total);
    if (pc.sub.points.empty()) return out;
    AddMomentsAndElevations(pc, up, out);
    const KdTree tree(pc.sub);
    const VoxelRsdResult voxels = ComputeVoxelRsd(pc.sub, tree, params.voxels);
    AddCurvatureCounts(voxels, pc, out);
    const std::vector<std::vector<std::uint32_t>> owned = VoxelsByMajorityOwner(voxels, pc);
    for (std::size_t p = 0; p < parts.size(); ++p) {
        if (owned[p].empty()) continue;
        const FeatureVector h = GrsdMinusOfVoxels(voxels, owned[p]);
        out.row(static_cast<Eigen::Index>(p)).head<kPartGrsdSize>() = h.transpose();
    }
    return out;
}

Row SubgraphDescriptor(const FeatureMatrix& descriptors, std::span<const std::uint32_t> vertices) {
    Row sum = Row::Zero();
    for (std::uint32_t v : vertices) {
        sum += descriptors.row(static_cast<Eigen::Index>(v));
    }
    return sum;
}

std::size_t PartGraphModel::AddObject(const FeatureMatrix& descriptors, const PartGraph& graph,
                                      Category category, const PartGraphTrainParams& params) {
    if (category == Category::kNone || static_cast<std::size_t>(category) >= kNumCategories) {
        throw InvalidArgument("training category must be a real category");
    }
    if (params.max_parts == 0 || params.max_parts > kMaxSubgraphParts) {
        throw InvalidArgument("max_parts must be in [1, 15]");
    }
    if (params.max_per_size == 0) throw InvalidArgument("max_per_size must be >= 1");
    if (static_cast<std::size_t>(descriptors.rows()) != graph.size() ||
        (descriptors.rows() > 0 && descriptors.cols() != kPartDescriptorSize)) {
        throw InvalidArgument("descriptors must have one row of kPartDescriptorSize per part");
    }
    if (graph.size() == 0) return 0;
    SplitMix rng{params.seed};
    std::vector<std::uint32_t> order(graph.size());
    std::iota(order.begin(), order.end(), 0u);
    for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng.Below(i)]);
    // Reservoir per size of (key, descriptor).
    struct Sample {
        std::uint64_t key;
        Row row;
    };
    std::vector<std::vector<Sample>> reservoir(params.max_parts + 1);
    std::vector<std::size_t> seen(params.max_parts + 1, 0);
    std::size_t visited = 0;
    EnumerateConnectedSubgraphs(
        graph, params.max_parts,
        [&](std::span<const std::uint32_t> vs) {
            const std::size_t s = vs.size();
            const std::size_t n = ++seen[s];
            if (reservoir[s].size() < params.max_per_size) {
                reservoir[s].push_back(
                    {SubgraphKey(graph, vs), SubgraphDescriptor(descriptors, vs)});
            } else {
                const std::uint64_t j = rng.Below(n);
                if (j < params.max_per_size) {
                    reservoir[s][j] = {SubgraphKey(graph, vs), SubgraphDescriptor(descriptors, vs)};
                }
            }
            return ++visited < params.max_visited;
        },
        order);
    std::size_t added = 0;
    float mapped[kPartMappedSize];
    for (const auto& samples : reservoir) {
        for (const Sample& sample : samples) {
            // No voxel of its own: nothing to learn.
            if (GrsdSum(sample.row.data()) <= 0.0f) continue;
            MapDescriptor(sample.row.data(), mapped);
            Bucket& b = buckets_[sample.key];
            b.rows.insert(b.rows.end(), mapped, mapped + kPartMappedSize);
            b.labels.push_back(static_cast<std::uint8_t>(category));
            ++added;
        }
    }
    train_max_parts = std::max(train_max_parts, params.max_parts);
    built_ = false;
    return added;
}

void PartGraphModel::MapDescriptor(const float* in, float* out) const {
    const PartDescriptorParams& dp = descriptor_params;
    // Unit-sum, square-rooted GRSD- (Euclidean distance = Jeffries-Matusita), elevation and
    // curvature counts the same way.
    MapCounts(in, kPartGrsdSize, dp.grsd_weight, out);
    MapCounts(in + kPartElevationOffset, kPartElevationSize, dp.elevation_weight,
              out + kPartGrsdSize + 3);
    MapCounts(in + kPartRsdOffset, kPartRsdSize, dp.rsd_weight,
              out + kPartGrsdSize + 3 + kPartElevationSize);
    // Extents of the group's points from its summed moments.
    const float* m = in + kPartMomentOffset;
    for (int j = 0; j < 3; ++j) out[kPartGrsdSize + j] = 0.0f;
    const double n = m[0];
    if (!(n >= 2.0) || dp.size_weight <= 0.0f) return;
    const Eigen::Vector3d mean(m[1] / n, m[2] / n, m[3] / n);
    Eigen::Matrix3d c;
    c << m[4] / n, m[5] / n, m[6] / n, m[5] / n, m[7] / n, m[8] / n, m[6] / n, m[8] / n, m[9] / n;
    c -= mean * mean.transpose();
    if (dp.upright_extents) {
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(c.topLeftCorner<2, 2>(),
                                                                Eigen::EigenvaluesOnly);
        const Eigen::Vector3d v(es.eigenvalues()[1], es.eigenvalues()[0], c(2, 2));
        for (int j = 0; j < 3; ++j) {
            const double extent = std::sqrt(12.0 * std::max(v[j], 0.0));
            out[kPartGrsdSize + j] =
                static_cast<float>(extent * dp.size_weight * dp.extent_weights[j]);
        }
        return;
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(c, Eigen::EigenvaluesOnly);
    const Eigen::Vector3d l = es.eigenvalues();  // ascending
    for (int j = 0; j < 3; ++j) {
        const double extent = std::sqrt(12.0 * std::max(l[2 - j], 0.0));
        out[kPartGrsdSize + j] = static_cast<float>(extent * dp.size_weight * dp.extent_weights[j]);
    }
}

void PartGraphModel::Build() {
    keys_by_size_.clear();
    for (auto& [key, b] : buckets_) {
        b.tree = ml::KdTreeNd(b.rows.data(), b.labels.size(), kPartMappedSize, 16);
        keys_by_size_[KeyParts(key)].push_back(key);
    }
    const auto counts = rows_per_category();
    std::size_t total = 0;
    for (auto c : counts) total += c;
    for (std::size_t c = 0; c < kNumCategories; ++c) {
        class_weight_[c] =
            counts[c] > 0 ? static_cast<float>(static_cast<double>(total) / counts[c]) : 0.0f;
    }
    built_ = true;
}

std::uint64_t PartGraphModel::ResolveKey(std::uint64_t key, bool* fallback) const {
    if (fallback) *fallback = false;
    if (buckets_.count(key)) return key;
    const auto it = keys_by_size_.find(KeyParts(key));
    if (it == keys_by_size_.end()) return 0;
    if (fallback) *fallback = true;
    const std::vector<int> want = KeyDegrees(key);
    std::uint64_t best = 0;
    int best_d = std::numeric_limits<int>::max();
    for (std::uint64_t k : it->second) {
        const std::vector<int> have = KeyDegrees(k);
        int d = 0;
        for (std::size_t i = 0; i < want.size(); ++i) d += std::abs(want[i] - have[i]);
        if (d < best_d) {
            best_d = d;
            best = k;
        }
    }
    return best;
}

std::array<float, kNumCategories> PartGraphModel::Classify(std::uint64_t key,
                                                           const float* descriptor, std::size_t k,
                                                           bool* fallback, bool balanced,
                                                           float distance_offset) const {
    if (!built_) throw InvalidArgument("part-graph model: Build() before Classify()");
    std::array<float, kNumCategories> p{};
    const std::uint64_t resolved = ResolveKey(key, fallback);
    if (resolved == 0) return p;
    const Bucket& b = buckets_.at(resolved);
    float q[kPartMappedSize];
    MapDescriptor(descriptor, q);
    thread_local std::vector<ml::Neighbour> nn;
    b.tree.Search(q, std::min(k, b.labels.size()), nn);
    if (nn.empty()) return p;
    float total = 0.0f;
    for (const auto& n : nn) {
        float w = balanced ? class_weight_[b.labels[n.row]] : 1.0f;
        if (distance_offset > 0.0f) w /= std::sqrt(n.distance) + distance_offset;
        p[b.labels[n.row]] += w;
        total += w;
    }
    if (total <= 0.0f) return {};
    for (float& v : p) v /= total;
    return p;
}

std::size_t PartGraphModel::num_rows() const {
    std::size_t n = 0;
    for (const auto& [k, b] : buckets_) n += b.labels.size();
    return n;
}

std::array<std::size_t, kNumCategories> PartGraphModel::rows_per_category() const {
    std::array<std::size_t, kNumCategories> n{};
    for (const auto& [k, b] : buckets_) {
        for (auto l : b.labels) ++n[l];
    }
    return n;
}

void PartGraphModel::AddCluster(const Eigen::VectorXf& descriptor, Category category) {
    if (category == Category::kNone || static_cast<std::size_t>(category) >= kNumCategories) {
        throw InvalidArgument("AddCluster: the category must be one of the six");
    }
    if (!descriptor.allFinite()) throw InvalidArgument("AddCluster: non-finite descriptor");
    if (descriptor.size() == 0 || descriptor.cwiseAbs().sum() == 0.0f) return;
    const auto dims = static_cast<std::size_t>(descriptor.size());
    if (cluster_dims_ != 0 && dims != cluster_dims_) {
        throw InvalidArgument(
            fmt::format("AddCluster: {} values, the model's rows have {}", dims, cluster_dims_));
    }
    cluster_dims_ = dims;
    cluster_rows_.insert(cluster_rows_.end(), descriptor.data(), descriptor.data() + dims);
    cluster_labels_.push_back(static_cast<std::uint8_t>(category));
}

std::array<float, kNumCategories> PartGraphModel::ClassifyCluster(const Eigen::VectorXf& descriptor,
                                                                  std::size_t k) const {
    std::array<float, kNumCategories> out{};
    if (cluster_labels_.empty() || k == 0 ||
        static_cast<std::size_t>(descriptor.size()) != cluster_dims_ ||
        descriptor.cwiseAbs().sum() == 0.0f || !descriptor.allFinite()) {
        return out;
    }
    std::vector<std::pair<float, std::size_t>> d(cluster_labels_.size());
    for (std::size_t i = 0; i < cluster_labels_.size(); ++i) {
        const Eigen::Map<const Eigen::VectorXf> row(cluster_rows_.data() + i * cluster_dims_,
                                                    static_cast<Eigen::Index>(cluster_dims_));
        d[i] = {(row - descriptor).squaredNorm(), i};
    }
    k = std::min(k, d.size());
    std::partial_sort(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(k), d.end());
    for (std::size_t i = 0; i < k; ++i) out[cluster_labels_[d[i].second]] += 1.0f / float(k);
    return out;
}

std::string PartGraphModel::Serialize() const {
    ml::ByteWriter w;
    w.Put<float>(descriptor_params.voxels.voxel_size);
    w.Put<float>(descriptor_params.voxels.rsd.radius);
    w.Put<float>(descriptor_params.voxels.rsd.angle_quantile);
    w.Put<float>(graph_params.adjacency_distance);
    w.Put<float>(descriptor_params.size_weight);
    for (float e : descriptor_params.extent_weights) w.Put<float>(e);
    w.Put<float>(descriptor_params.grsd_weight);
    w.Put<float>(descriptor_params.elevation_weight);
    w.Put<float>(descriptor_params.rsd_weight);
    w.Put<std::uint8_t>(descriptor_params.upright_extents ? 1 : 0);
    w.Put<std::uint64_t>(train_max_parts);
    w.Put<std::uint64_t>(buckets_.size());
    for (const auto& [key, b] : buckets_) {
        w.Put<std::uint64_t>(key);
        w.PutVector(b.labels);
        w.PutVector(b.rows);
    }
    w.Put<float>(cluster_size_weight);
    w.Put<std::uint64_t>(cluster_dims_);
    w.PutVector(cluster_labels_);
    w.PutVector(cluster_rows_);
    w.PutVector(stacker.Parameters());
    return ml::WrapContainer(kMagic, kPartGraphModelVersion, w.bytes());
}

PartGraphModel PartGraphModel::Deserialize(const std::string& bytes, const std::string& what) {
    const std::string payload =
        ml::UnwrapContainer(bytes, kMagic, kPartGraphModelVersion, "part-graph model", what);
    ml::ByteReader r(payload, what);
    PartGraphModel m;
    m.descriptor_params.voxels.voxel_size = r.Get<float>();
    m.descriptor_params.voxels.rsd.radius = r.Get<float>();
    m.descriptor_params.voxels.rsd.angle_quantile = r.Get<float>();
    m.graph_params.adjacency_distance = r.Get<float>();
    m.descriptor_params.size_weight = r.Get<float>();
    for (float& e : m.descriptor_params.extent_weights) e = r.Get<float>();
    m.descriptor_params.grsd_weight = r.Get<float>();
    m.descriptor_params.elevation_weight = r.Get<float>();
    m.descriptor_params.rsd_weight = r.Get<float>();
    const auto upright = r.Get<std::uint8_t>();
    if (upright > 1) r.Fail("bad parameters");
    m.descriptor_params.upright_extents = upright == 1;
    m.train_max_parts = r.Get<std::uint64_t>();
    bool weights_ok = true;
    try {
        ValidateDescriptorParams(m.descriptor_params);
    } catch (const InvalidArgument&) {
        weights_ok = false;
    }
    if (!(m.descriptor_params.voxels.voxel_size > 0.0f) ||
        !(m.graph_params.adjacency_distance > 0.0f) ||
        !std::isfinite(m.descriptor_params.voxels.rsd.radius) || !weights_ok ||
        m.train_max_parts == 0 || m.train_max_parts > kMaxSubgraphParts) {
        r.Fail("bad parameters");
    }
    const auto nb = r.Get<std::uint64_t>();
    for (std::uint64_t i = 0; i < nb; ++i) {
        const auto key = r.Get<std::uint64_t>();
        Bucket b;
        b.labels = r.GetVector<std::uint8_t>();
        b.rows = r.GetVector<float>();
        const std::size_t parts = KeyParts(key);
        if (parts == 0 || b.labels.empty() || b.rows.size() != b.labels.size() * kPartMappedSize ||
            m.buckets_.count(key)) {
            r.Fail("bad bucket");
        }
        for (auto l : b.labels) {
            if (l == 0 || l >= kNumCategories) r.Fail("bad category");
        }
        for (std::size_t j = 0; j < b.rows.size(); ++j) {
            const float v = b.rows[j];
            if (!std::isfinite(v) || v < 0.0f) r.Fail("bad descriptor");
        }
        m.buckets_.emplace(key, std::move(b));
    }
    m.cluster_size_weight = r.Get<float>();
    if (!(m.cluster_size_weight >= 0.0f) || !std::isfinite(m.cluster_size_weight)) {
        r.Fail("bad cluster parameters");
    }
    m.cluster_dims_ = r.Get<std::uint64_t>();
    m.cluster_labels_ = r.GetVector<std::uint8_t>();
    m.cluster_rows_ = r.GetVector<float>();
    if (m.cluster_rows_.size() != m.cluster_labels_.size() * m.cluster_dims_ ||
        (m.cluster_dims_ == 0) != m.cluster_labels_.empty()) {
        r.Fail("bad cluster rows");
    }
    for (auto l : m.cluster_labels_) {
        if (l == 0 || l >= kNumCategories) r.Fail("bad category");
    }
    for (float v : m.cluster_rows_) {
        if (!std::isfinite(v)) r.Fail("bad cluster descriptor");
    }
    m.stacker = CategoryStacker::FromParameters(r.GetVector<float>(), what);
    if (!r.AtEnd()) r.Fail("trailing bytes");
    m.Build();
    return m;
}

void PartGraphModel::Save(const std::filesystem::path& path) const {
    ml::WriteBytesAtomically(path, Serialize());
}

PartGraphModel PartGraphModel::Load(const std::filesystem::path& path) {
    return Deserialize(ml::ReadBytes(path), path.string());
}

PartGraphResult RecognizeParts(const PartGraphModel& model, const PointCloud& cloud,
                               const std::vector<Indices>& parts,
                               const PartGraphRecognitionParams& params, const Eigen::Vector3f& up,
                               std::span<const std::uint32_t> groups) {
    const PartGraph graph = BuildPartGraph(cloud, parts, model.graph_params);
    const FeatureMatrix d = ComputePartDescriptors(cloud, parts, model.descriptor_params, up);
    return RecognizeParts(model, graph, d, params, groups);
}

namespace {

// The graph without the edges between parts of different groups.
PartGraph WithinGroups(const PartGraph& graph, std::span<const std::uint32_t> groups) {
    PartGraph out(graph.size());
    for (std::uint32_t a = 0; a < graph.size(); ++a) {
        for (std::uint32_t b : graph.Neighbours(a)) {
            if (a < b && groups[a] == groups[b]) out.AddEdge(a, b);
        }
    }
    return out;
}

// Connected components of a graph, each ascending.
std::vector<std::vector<std::uint32_t>> Components(const PartGraph& graph) {
    std::vector<std::vector<std::uint32_t>> out;
    std::vector<bool> seen(graph.size(), false);
    for (std::uint32_t s = 0; s < graph.size(); ++s) {
        if (seen[s]) continue;
        std::vector<std::uint32_t> comp{s};
        seen[s] = true;
        for (std::size_t i = 0; i < comp.size(); ++i) {
            for (std::uint32_t b : graph.Neighbours(comp[i])) {
                if (!seen[b]) {
                    seen[b] = true;
                    comp.push_back(b);
                }
            }
        }
        std::sort(comp.begin(), comp.end());
        out.push_back(std::move(comp));
    }
    return out;
}

}  // namespace

void PartGraphRecognitionParams::Validate() const {
    if (k == 0) throw InvalidArgument("k must be >= 1");
    if (!(group_weight >= 0.0f) || !std::isfinite(group_weight)) {
        throw InvalidArgument("group_weight must be >= 0 and finite");
    }
    if (!(size_exponent >= 0.0f)) throw InvalidArgument("size_exponent must be >= 0");
    if (!(distance_offset > 0.0f) || !std::isfinite(distance_offset)) {
        throw InvalidArgument("distance_offset must be > 0 and finite");
    }
    float prior_sum = 0.0f;
    for (std::size_t c = 1; c < kNumCategories; ++c) {
        const float w = category_priors[c];
        if (!(w >= 0.0f) || !std::isfinite(w)) {
            throw InvalidArgument("category priors must be >= 0 and finite");
        }
        prior_sum += w;
    }
    if (!(prior_sum > 0.0f)) throw InvalidArgument("category priors: at least one must be > 0");
}

PartGraphResult RecognizeParts(const PartGraphModel& model, const PartGraph& graph,
                               const FeatureMatrix& descriptors,
                               const PartGraphRecognitionParams& params,
                               std::span<const std::uint32_t> groups) {
    params.Validate();
    if (!groups.empty() && groups.size() != graph.size()) {
        throw InvalidArgument(fmt::format("groups must have one entry per part ({}), got {}",
                                          graph.size(), groups.size()));
    }
    if (static_cast<std::size_t>(descriptors.rows()) != graph.size() ||
        (descriptors.rows() > 0 && descriptors.cols() != kPartDescriptorSize)) {
        throw InvalidArgument("descriptors must have one row of kPartDescriptorSize per part");
    }
    PartGraphResult result;
    const std::size_t n = graph.size();
    result.part_probabilities.assign(n, {});
    result.part_categories.assign(n, Category::kNone);
    if (n == 0) return result;
    const std::size_t max_parts = std::min(params.max_parts, model.train_max_parts);
    // The groups' own graph: what votes with within_groups, and whose components are the
    // wholes of group_weight.
    const PartGraph within = groups.empty() ? PartGraph() : WithinGroups(graph, groups);
    const PartGraph& g = !groups.empty() && params.within_groups ? within : graph;
    // One subgraph's vote on its parts: `scale` times (confidence or 1).
    auto vote = [&](std::span<const std::uint32_t> vs, float scale) {
        const Row desc = SubgraphDescriptor(descriptors, vs);
        if (GrsdSum(desc.data()) <= 0.0f) return;
        bool fallback = false;
        const auto p =
            model.Classify(SubgraphKey(g, vs), desc.data(), params.k, &fallback, params.balanced,
                           params.distance_weighted ? params.distance_offset : 0.0f);
        float conf = *std::max_element(p.begin(), p.end());
        if (conf <= 0.0f) return;
        ++result.subgraphs;
        if (fallback) ++result.fallbacks;
        const float w = (params.confidence_weighted ? conf : 1.0f) * scale;
        for (std::uint32_t v : vs) {
            for (std::size_t c = 0; c < kNumCategories; ++c) {
                result.part_probabilities[v][c] += w * p[c];
            }
        }
    };
    EnumerateConnectedSubgraphs(g, max_parts, [&](std::span<const std::uint32_t> vs) {
        vote(vs, 1.0f / std::pow(static_cast<float>(vs.size()), params.size_exponent));
        return result.subgraphs < params.max_subgraphs;
    });
    if (!groups.empty() && params.group_weight > 0.0f) {
        for (const auto& comp : Components(within)) {
            if (comp.size() > model.train_max_parts) continue;
            vote(comp, params.group_weight);
        }
    }
    for (std::size_t v = 0; v < n; ++v) {
        auto& p = result.part_probabilities[v];
        p = ApplyCategoryPriors(p, params.category_priors);
        if (p == std::array<float, kNumCategories>{}) p[0] = 1.0f;  // no vote
        result.part_categories[v] = ArgMaxCategory(p);
    }
    return result;
}

std::array<float, kNumCategories> MergePartProbabilities(const PartGraphResult& result,
                                                         const std::vector<Indices>& parts,
                                                         const std::vector<std::size_t>& part_ids) {
    std::array<float, kNumCategories> p{};
    double total = 0.0;
    for (std::size_t id : part_ids) {
        if (id >= result.part_probabilities.size() || id >= parts.size()) {
            throw InvalidArgument("part id out of range");
        }
        const auto w = static_cast<float>(parts[id].size());
        for (std::size_t c = 0; c < kNumCategories; ++c) {
            p[c] += w * result.part_probabilities[id][c];
        }
        total += w;
    }
    if (total <= 0.0) {
        p = {};
        p[0] = 1.0f;
        return p;
    }
    for (float& x : p) x = static_cast<float>(x / total);
    return p;
}

VoxelVoteGrid::VoxelVoteGrid(float voxel_size) : voxel_(voxel_size) {
    if (!(voxel_size > 0.0f) || !std::isfinite(voxel_size)) {
        throw InvalidArgument("voxel_size must be > 0 and finite");
    }
}

namespace {
std::array<int, 3> Cell(const Eigen::Vector3f& p, float s) {
    return {static_cast<int>(std::floor(p.x() / s)), static_cast<int>(std::floor(p.y() / s)),
            static_cast<int>(std::floor(p.z() / s))};
}
}  // namespace

void VoxelVoteGrid::Add(const std::vector<Eigen::Vector3f>& points,
                        const std::vector<std::array<float, kNumCategories>>& votes) {
    if (points.size() != votes.size()) {
        throw InvalidArgument("votes must have one distribution per point");
    }
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (!points[i].allFinite()) continue;
        auto& cell = cells_[Cell(points[i], voxel_)];
        for (std::size_t c = 0; c < kNumCategories; ++c) cell[c] += votes[i][c];
    }
}

std::array<float, kNumCategories> VoxelVoteGrid::Votes(const Eigen::Vector3f& point) const {
    if (!point.allFinite()) return {};
    const auto it = cells_.find(Cell(point, voxel_));
    return it == cells_.end() ? std::array<float, kNumCategories>{} : it->second;
}

Category VoxelVoteGrid::CategoryAt(const Eigen::Vector3f& point) const {
    const auto v = Votes(point);
    if (*std::max_element(v.begin(), v.end()) <= 0.0f) return Category::kNone;
    return ArgMaxCategory(v);
}

}  // namespace multicue
