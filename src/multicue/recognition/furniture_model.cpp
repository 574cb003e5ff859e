#include "multicue/recognition/furniture_model.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/ml/kmeans.hpp"
#include "multicue/ml/serialization.hpp"

namespace multicue {
namespace {

constexpr std::string_view kFurnitureMagic = "MCFURNIT";

}  // namespace

const char* FurnitureFeatureSetName(FurnitureFeatureSet set) {
    return set == FurnitureFeatureSet::kFull ? "full" : "reduced";
}

FurnitureFeatureSet ParseFurnitureFeatureSet(std::string_view name) {
    if (name == "full") return FurnitureFeatureSet::kFull;
    if (name == "reduced") return FurnitureFeatureSet::kReduced;
    throw InvalidArgument(fmt::format("feature set must be full or reduced, got '{}'", name));
}

std::vector<int> FurnitureFeatureColumns(FurnitureFeatureSet set) {
    std::vector<int> cols;
    for (int c = 0; c < kPartStatsSize; ++c) {
        // Features 4 (eigenvalue ratios, columns 3-8), 7 (extents and their ratios, 13-19) and
        // 8 (v_k / L_k, 20-22) of section 4.2.3.1.
        const bool dropped = (c >= 3 && c <= 8) || (c >= 13 && c <= 22);
        if (set == FurnitureFeatureSet::kFull || !dropped) cols.push_back(c);
    }
    return cols;
}

const char* FurnitureActivationName(FurnitureActivation activation) {
    return activation == FurnitureActivation::kWords ? "words" : "nearest-part";
}

FurnitureActivation ParseFurnitureActivation(std::string_view name) {
    if (name == "words") return FurnitureActivation::kWords;
    if (name == "nearest-part") return FurnitureActivation::kNearestPart;
    throw InvalidArgument(fmt::format("activation must be words or nearest-part, got '{}'", name));
}

void FurnitureVocabularyParams::Validate() const {
    if (words < 1) throw InvalidArgument("furniture vocabulary: words must be >= 1");
    if (max_iterations < 1)
        throw InvalidArgument("furniture vocabulary: max_iterations must be >= 1");
    if (num_threads < 0) throw InvalidArgument("furniture vocabulary: num_threads must be >= 0");
}

FurnitureModel FurnitureModel::Train(std::vector<FurnitureTrainingPart> parts,
                                     std::vector<FurnitureClass> classes,
                                     std::vector<FurnitureCad> cads,
                                     const FurniturePartParams& part_params,
                                     const FurnitureVocabularyParams& params) {
    params.Validate();
    part_params.Validate();
    if (parts.empty()) throw InvalidArgument("furniture vocabulary: no training parts");
    if (classes.empty()) throw InvalidArgument("furniture vocabulary: no classes");
    const int n_classes = static_cast<int>(classes.size());
    for (const auto& c : classes) {
        if (!(c.width > 0.0f) || !(c.length > 0.0f) || !(c.height > 0.0f) ||
            !std::isfinite(c.width) || !(c.threshold >= 0.0f) || !std::isfinite(c.threshold)) {
            throw InvalidArgument(
                fmt::format("furniture class '{}': width, length and height must "
                            "be > 0 and the threshold >= 0",
                            c.name));
        }
    }
    for (const auto& p : parts) {
        if (p.cls < 0 || p.cls >= n_classes) {
            throw InvalidArgument(
                fmt::format("furniture training part of unknown class {}", p.cls));
        }
        if (p.features.size() != kPartStatsSize) {
            throw InvalidArgument(fmt::format("furniture training part has {} features, not {}",
                                              p.features.size(), kPartStatsSize));
        }
        if (!p.features.allFinite() || !p.offset.allFinite()) {
            throw DataError("furniture training part with non-finite features or offset");
        }
    }
    for (const auto& c : cads) {
        if (c.cls < 0 || c.cls >= n_classes) {
            throw InvalidArgument(fmt::format("CAD model '{}' of unknown class {}", c.id, c.cls));
        }
    }
    FurnitureModel m;
    m.parts_ = std::move(parts);
    m.classes_ = std::move(classes);
    m.cads_ = std::move(cads);
    m.part_params_ = part_params;
    m.vocabulary_params_ = params;
    m.columns_ = FurnitureFeatureColumns(params.features);
    m.Derive();
    ml::KMeansParams kp;
    kp.k = std::min(params.words, m.parts_.size());
    kp.max_iterations = params.max_iterations;
    kp.seed = params.seed;
    kp.num_threads = params.num_threads;
    const ml::KMeansResult km = ml::KMeans(m.normalized_parts_, kp);
    m.words_ = km.centers;
    m.part_words_ = km.assignment;
    m.Index();
    return m;
}

void FurnitureModel::Derive() {
    const std::size_t d = columns_.size();
    lo_.assign(d, 0.0f);
    scale_.assign(d, 0.0f);
    for (std::size_t j = 0; j < d; ++j) {
        float lo = parts_.front().features[columns_[j]], hi = lo;
        for (const auto& p : parts_) {
            lo = std::min(lo, p.features[columns_[j]]);
            hi = std::max(hi, p.features[columns_[j]]);
        }
        lo_[j] = lo;
        scale_[j] = hi > lo ? 1.0f / (hi - lo) : 0.0f;
    }
    max_part_extent_ = 0.0f;
    max_object_height_ = 0.0f;
    for (const auto& p : parts_) max_part_extent_ = std::max(max_part_extent_, p.features[15]);
    for (const auto& c : classes_) max_object_height_ = std::max(max_object_height_, c.height);
    for (const auto& c : cads_) max_object_height_ = std::max(max_object_height_, c.extent.z());
    normalized_parts_.resize(static_cast<Eigen::Index>(parts_.size()),
                             static_cast<Eigen::Index>(d));
    for (std::size_t i = 0; i < parts_.size(); ++i) {
        Normalize({parts_[i].features.data(), kPartStatsSize},
                  normalized_parts_.data() + static_cast<Eigen::Index>(i * d));
    }
}

void FurnitureModel::Index() {
    word_elements_.assign(num_words(), {});
    word_class_counts_.assign(num_words(), std::vector<float>(classes_.size(), 0.0f));
    for (std::size_t i = 0; i < parts_.size(); ++i) {
        const auto w = static_cast<std::size_t>(part_words_[i]);
        word_elements_[w].push_back(static_cast<int>(i));
        word_class_counts_[w][static_cast<std::size_t>(parts_[i].cls)] += 1.0f;
    }
}

float FurnitureModel::WordClassCount(int w, int cls) const {
    return word_class_counts_.at(static_cast<std::size_t>(w)).at(static_cast<std::size_t>(cls));
}

int FurnitureModel::ClassIndex(std::string_view name) const {
    for (std::size_t c = 0; c < classes_.size(); ++c) {
        if (classes_[c].name == name) return static_cast<int>(c);
    }
    return -1;
}

void FurnitureModel::Normalize(std::span<const float> in, float* out) const {
    for (std::size_t j = 0; j < columns_.size(); ++j) {
        out[j] = std::clamp((in[static_cast<std::size_t>(columns_[j])] - lo_[j]) * scale_[j], 0.0f,
                            1.0f);
    }
}

std::vector<std::pair<int, float>> FurnitureModel::Activate(std::span<const float> features,
                                                            FurnitureActivation mode,
                                                            std::size_t activations) const {
    if (!trained()) throw InvalidArgument("furniture model: train or load it before use");
    if (features.size() != kPartStatsSize) {
        throw InvalidArgument(fmt::format("furniture model: a part has {} features, not {}",
                                          features.size(), kPartStatsSize));
    }
    if (activations == 0) throw InvalidArgument("furniture model: activations must be >= 1");
    for (float x : features) {
        if (!std::isfinite(x)) throw DataError("furniture model: non-finite part feature");
    }
    const std::size_t d = columns_.size();
    float f[kPartStatsSize];
    Normalize(features, f);
    auto distance = [&](const float* c) {
        float s = 0.0f;
        for (std::size_t j = 0; j < d; ++j) s += (f[j] - c[j]) * (f[j] - c[j]);
        return std::sqrt(s);
    };
    if (mode == FurnitureActivation::kNearestPart) {
        int best = 0;
        float best_d = std::numeric_limits<float>::infinity();
        for (Eigen::Index i = 0; i < normalized_parts_.rows(); ++i) {
            const float di = distance(normalized_parts_.data() + i * static_cast<Eigen::Index>(d));
            if (di < best_d) best_d = di, best = static_cast<int>(i);
        }
        return {{best, 1.0f}};
    }
    std::vector<std::pair<float, int>> dist(num_words());
    for (std::size_t w = 0; w < num_words(); ++w) {
        dist[w] = {distance(words_.data() + static_cast<Eigen::Index>(w * d)), static_cast<int>(w)};
    }
    const std::size_t m = std::min(activations, dist.size());
    std::partial_sort(dist.begin(), dist.begin() + static_cast<std::ptrdiff_t>(m), dist.end());
    std::vector<std::pair<int, float>> out(m);
    double sum = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
        // Eq. (4.3): w(f, A_i) proportional to the inverse Euclidean distance.
        const float w = 1.0f / (dist[i].first + 1e-6f);
        out[i] = {dist[i].second, w};
        sum += w;
    }
    for (auto& [w, p] : out) p = static_cast<float>(p / sum);
    return out;
}

// ---------------------------------------------------------------------------------------------
// Model file.

namespace {

void PutCloud(ml::ByteWriter& w, const PointCloud& c) {
    std::vector<float> p, n;
    for (std::size_t i = 0; i < c.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            p.push_back(c.points[i][k]);
            n.push_back(c.normals.size() == c.size() ? c.normals[i][k] : 0.0f);
        }
    }
    w.PutVector(p);
    w.PutVector(n);
}

PointCloud GetCloud(ml::ByteReader& r) {
    const auto p = r.GetVector<float>(), n = r.GetVector<float>();
    if (p.size() % 3 != 0 || n.size() != p.size()) r.Fail("bad CAD point cloud");
    PointCloud c;
    for (std::size_t i = 0; i < p.size(); i += 3) {
        c.points.emplace_back(p[i], p[i + 1], p[i + 2]);
        c.normals.emplace_back(n[i], n[i + 1], n[i + 2]);
        if (!c.points.back().allFinite() || !c.normals.back().allFinite())
            r.Fail("non-finite CAD point");
    }
    c.width = static_cast<std::uint32_t>(c.points.size());
    return c;
}

void PutMesh(ml::ByteWriter& w, const TriangleMesh& m) {
    std::vector<float> v;
    std::vector<std::uint32_t> t;
    for (const auto& p : m.vertices) v.insert(v.end(), {p.x(), p.y(), p.z()});
    for (const auto& tri : m.triangles) t.insert(t.end(), {tri[0], tri[1], tri[2]});
    w.PutVector(v);
    w.PutVector(t);
}

TriangleMesh GetMesh(ml::ByteReader& r) {
    const auto v = r.GetVector<float>();
    const auto t = r.GetVector<std::uint32_t>();
    if (v.size() % 3 != 0 || t.size() % 3 != 0) r.Fail("bad CAD mesh");
    TriangleMesh m;
    for (std::size_t i = 0; i < v.size(); i += 3) m.vertices.emplace_back(v[i], v[i + 1], v[i + 2]);
    for (std::size_t i = 0; i < t.size(); i += 3) {
        if (t[i] >= m.vertices.size() || t[i + 1] >= m.vertices.size() ||
            t[i + 2] >= m.vertices.size()) {
            r.Fail("CAD mesh triangle index out of range");
        }
        m.triangles.emplace_back(t[i], t[i + 1], t[i + 2]);
    }
    return m;
}

void PutPartParams(ml::ByteWriter& w, const FurniturePartParams& p) {
    w.Put<float>(p.voxel_size);
    w.Put<float>(p.floor_margin);
    w.Put<float>(p.max_height);
    w.Put<std::uint8_t>(p.estimate_floor ? 1 : 0);
    w.Put<float>(p.normal_radius);
    w.Put<std::int32_t>(p.normal_k);
    w.Put<float>(p.smoothing_radius);
    w.Put<float>(p.region_growing.radius);
    w.Put<std::int32_t>(p.region_growing.k);
    w.Put<float>(p.region_growing.max_angle_deg);
    w.Put<std::uint64_t>(p.region_growing.min_part_size);
    w.Put<std::uint8_t>(p.region_growing.discard_small_parts ? 1 : 0);
    w.Put<std::uint64_t>(p.min_part_points);
    w.Put<float>(p.stats.radius);
    w.Put<float>(p.stats.voxel_size);
    w.Put<float>(p.stats.boundary_angle);
    w.Put<std::uint8_t>(static_cast<std::uint8_t>(p.frame));
}

FurniturePartParams GetPartParams(ml::ByteReader& r) {
    FurniturePartParams p;
    p.voxel_size = r.Get<float>();
    p.floor_margin = r.Get<float>();
    p.max_height = r.Get<float>();
    p.estimate_floor = r.Get<std::uint8_t>() != 0;
    p.normal_radius = r.Get<float>();
    p.normal_k = r.Get<std::int32_t>();
    p.smoothing_radius = r.Get<float>();
    p.region_growing.radius = r.Get<float>();
    p.region_growing.k = r.Get<std::int32_t>();
    p.region_growing.max_angle_deg = r.Get<float>();
    p.region_growing.min_part_size = r.Get<std::uint64_t>();
    p.region_growing.discard_small_parts = r.Get<std::uint8_t>() != 0;
    p.min_part_points = r.Get<std::uint64_t>();
    p.stats.radius = r.Get<float>();
    p.stats.voxel_size = r.Get<float>();
    p.stats.boundary_angle = r.Get<float>();
    const auto frame = r.Get<std::uint8_t>();
    if (frame > 1) r.Fail("bad part frame");
    p.frame = static_cast<FurniturePartFrame>(frame);
    try {
        p.Validate();
    } catch (const InvalidArgument& e) {
        r.Fail(std::string("bad part parameters: ") + e.what());
    }
    return p;
}

}  // namespace

void FurnitureModel::SetVerifier(std::shared_ptr<const ml::Classifier> verifier) {
    if (verifier) {
        if (!verifier->fitted())
            throw InvalidArgument("furniture model: the verifier is not trained");
        const auto& names = verifier->class_names();
        if (names.size() != 2 || std::find(names.begin(), names.end(), "right") == names.end() ||
            std::find(names.begin(), names.end(), "wrong") == names.end()) {
            throw InvalidArgument(
                "furniture model: the verifier must have the classes \"right\" and \"wrong\"");
        }
    }
    verifier_ = std::move(verifier);
}

void FurnitureModel::Save(const std::filesystem::path& path) const {
    if (!trained()) throw InvalidArgument("furniture model: nothing to save before training");
    ml::ByteWriter w;
    PutPartParams(w, part_params_);
    w.Put<std::uint64_t>(vocabulary_params_.words);
    w.Put<std::uint64_t>(vocabulary_params_.max_iterations);
    w.Put<std::uint32_t>(vocabulary_params_.seed);
    w.Put<std::uint8_t>(static_cast<std::uint8_t>(vocabulary_params_.features));
    w.Put<std::uint64_t>(classes_.size());
    for (const auto& c : classes_) {
        w.PutString(c.name);
        w.Put<float>(c.width);
        w.Put<float>(c.length);
        w.Put<float>(c.height);
        w.Put<float>(c.threshold);
    }
    w.Put<std::uint64_t>(parts_.size());
    for (std::size_t i = 0; i < parts_.size(); ++i) {
        const auto& p = parts_[i];
        w.Put<std::int32_t>(p.cls);
        w.Put<std::int32_t>(p.piece);
        w.Put<std::int32_t>(p.view);
        w.Put<std::int32_t>(part_words_[i]);
        w.Put<float>(p.offset.x());
        w.Put<float>(p.offset.y());
        w.Put<float>(p.offset.z());
        w.Put<float>(p.centre_z);
        w.PutArray(p.features.data(), static_cast<std::size_t>(p.features.size()));
    }
    w.Put<std::uint64_t>(num_words());
    w.PutArray(words_.data(), static_cast<std::size_t>(words_.size()));
    w.Put<std::uint64_t>(cads_.size());
    for (const auto& c : cads_) {
        w.PutString(c.id);
        w.Put<std::int32_t>(c.cls);
        w.Put<float>(c.extent.x());
        w.Put<float>(c.extent.y());
        w.Put<float>(c.extent.z());
        PutCloud(w, c.cloud);
        PutMesh(w, c.mesh);
    }
    w.Put<std::uint8_t>(verifier_ ? 1 : 0);
    if (verifier_) w.PutString(verifier_->Serialize());
    ml::WriteContainer(path, kFurnitureMagic, kFormatVersion, w.bytes());
}

FurnitureModel FurnitureModel::Load(const std::filesystem::path& path) {
    const std::string bytes = ml::ReadBytes(path);
    const std::uint32_t version = ml::ContainerVersion(bytes);
    if (bytes.size() >= 8 && bytes.compare(0, 8, kFurnitureMagic) == 0 && version != 1 &&
        version != kFormatVersion) {
        throw FormatError(fmt::format(
            "{}: furniture model format version {} is not supported (this build reads versions 1 "
            "to {})",
            path.string(), version, kFormatVersion));
    }
    const std::string payload =
        ml::UnwrapContainer(bytes, kFurnitureMagic, version == 1 ? 1 : kFormatVersion,
                            "furniture model", path.string());
    ml::ByteReader r(payload, path.string());
    FurnitureModel m;
    m.part_params_ = GetPartParams(r);
    m.vocabulary_params_.words = r.Get<std::uint64_t>();
    m.vocabulary_params_.max_iterations = r.Get<std::uint64_t>();
    m.vocabulary_params_.seed = r.Get<std::uint32_t>();
    const auto set = r.Get<std::uint8_t>();
    if (set > 1) r.Fail("bad feature set");
    m.vocabulary_params_.features = static_cast<FurnitureFeatureSet>(set);
    const auto n_classes = r.Get<std::uint64_t>();
    if (n_classes == 0 || n_classes > 1000) r.Fail("bad class count");
    for (std::uint64_t c = 0; c < n_classes; ++c) {
        FurnitureClass k;
        k.name = r.GetString();
        k.width = r.Get<float>();
        k.length = r.Get<float>();
        k.height = r.Get<float>();
        k.threshold = r.Get<float>();
        if (!(k.width > 0.0f) || !(k.length > 0.0f) || !(k.height > 0.0f) ||
            !(k.threshold >= 0.0f) || !std::isfinite(k.width) || !std::isfinite(k.length) ||
            !std::isfinite(k.height) || !std::isfinite(k.threshold)) {
            r.Fail("bad class " + k.name);
        }
        m.classes_.push_back(k);
    }
    const auto n_parts = r.Get<std::uint64_t>();
    if (n_parts == 0) r.Fail("no training parts");
    m.parts_.reserve(std::min<std::uint64_t>(n_parts, payload.size() / 16));
    for (std::uint64_t i = 0; i < n_parts; ++i) {
        FurnitureTrainingPart p;
        p.cls = r.Get<std::int32_t>();
        p.piece = r.Get<std::int32_t>();
        p.view = r.Get<std::int32_t>();
        m.part_words_.push_back(r.Get<std::int32_t>());
        p.offset.x() = r.Get<float>();
        p.offset.y() = r.Get<float>();
        p.offset.z() = r.Get<float>();
        p.centre_z = r.Get<float>();
        const auto f = r.GetVector<float>(kPartStatsSize);
        if (f.size() != kPartStatsSize || p.cls < 0 || p.cls >= static_cast<int>(n_classes)) {
            r.Fail("bad training part");
        }
        p.features = Eigen::Map<const FeatureVector>(f.data(), kPartStatsSize);
        if (!p.features.allFinite() || !p.offset.allFinite() || !std::isfinite(p.centre_z))
            r.Fail("non-finite training part");
        m.parts_.push_back(std::move(p));
    }
    const auto k = r.Get<std::uint64_t>();
    m.columns_ = FurnitureFeatureColumns(m.vocabulary_params_.features);
    const auto words = r.GetVector<float>();
    if (k == 0 || words.size() != k * m.columns_.size()) r.Fail("bad vocabulary size");
    m.words_ = Eigen::Map<const FeatureMatrix>(words.data(), static_cast<Eigen::Index>(k),
                                               static_cast<Eigen::Index>(m.columns_.size()));
    if (!m.words_.allFinite()) r.Fail("non-finite word");
    for (int w : m.part_words_) {
        if (w < 0 || static_cast<std::uint64_t>(w) >= k) r.Fail("training part of an unknown word");
    }
    const auto n_cads = r.Get<std::uint64_t>();
    for (std::uint64_t i = 0; i < n_cads; ++i) {
        FurnitureCad c;
        c.id = r.GetString();
        c.cls = r.Get<std::int32_t>();
        c.extent.x() = r.Get<float>();
        c.extent.y() = r.Get<float>();
        c.extent.z() = r.Get<float>();
        if (c.cls < 0 || c.cls >= static_cast<int>(n_classes) || !c.extent.allFinite()) {
            r.Fail("bad CAD model " + c.id);
        }
        c.cloud = GetCloud(r);
        c.mesh = GetMesh(r);
        m.cads_.push_back(std::move(c));
    }
    if (version >= 2 && r.Get<std::uint8_t>() != 0) {
        const std::string what = path.string() + " (verifier)";
        std::shared_ptr<const ml::Classifier> verifier =
            ml::DeserializeClassifier(r.GetString(), what);
        try {
            m.SetVerifier(std::move(verifier));
        } catch (const InvalidArgument& e) {
            r.Fail(std::string("bad verifier: ") + e.what());
        }
    }
    if (!r.AtEnd()) r.Fail("trailing bytes");
    m.Derive();
    m.Index();
    return m;
}

}  // namespace multicue
