#include "multicue/recognition/dataset_extraction.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <unordered_set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/filters/voxel_grid.hpp"
#include "multicue/io/json_text.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// FNV-1a, 64 bits, cut to 63 so that group ids stay non-negative.
std::int64_t StableId(const std::string& text) {
    std::uint64_t h = 14695981039346656037ull;
    for (const unsigned char c : text) {
        h ^= c;
        h *= 1099511628211ull;
    }
    return static_cast<std::int64_t>(h & 0x7fffffffffffffffull);
}

bool IsMeshFile(const std::string& source) {
    const std::string ext = fs::path(source).extension().string();
    return !ext.empty() && ext.size() <= 5;
}

/// The file part of a row source ("frame.pcd#20" -> "frame.pcd").
std::string FileOfSource(const std::string& source) {
    const auto hash = source.rfind('#');
    return hash == std::string::npos ? source : source.substr(0, hash);
}

template <typename T>
T Get(const json& j, const char* key, const fs::path& manifest) {
    if (!j.is_object() || !j.contains(key)) {
        throw FormatError(fmt::format("{}: missing \"{}\"", manifest.string(), key));
    }
    const json& value = j.at(key);
    const auto wrong_type = [&] {
        return FormatError(fmt::format("{}: \"{}\" has the wrong type", manifest.string(), key));
    };
    if constexpr (std::is_integral_v<T>) {
        // get<T>() would cut a value beyond T (or a fraction) to another value.
        if (!io::JsonIntegerFits<T>(value)) throw wrong_type();
    }
    try {
        return value.get<T>();
    } catch (const json::exception&) {
        throw wrong_type();
    }
}

/// Throws InvalidArgument for a parameter out of range, before any file is read.
void CheckExtractionParams(const DatasetExtractionParams& params) {
    if (!(params.voxel_size >= 0.0f) || !std::isfinite(params.voxel_size)) {
        throw InvalidArgument("voxel_size must be >= 0");
    }
    if (!(params.normal_radius > 0.0f) || !std::isfinite(params.normal_radius)) {
        throw InvalidArgument("normal_radius must be > 0");
    }
    if (params.save_every == 0) throw InvalidArgument("save_every must be >= 1");
}

/// The dataset being extracted and its file. Rows not yet saved are saved before an error
/// propagates, so that --resume continues where the extraction stopped.
struct DatasetOutput {
    ml::Dataset data;
    fs::path out;
    std::size_t since_save = 0;
    bool dirty = false;

    void Save() {
        ml::WriteDatasetFile(data, out);
        since_save = 0;
        dirty = false;
    }
    void SaveIfDirty() {
        if (dirty) Save();
    }
};

/// --resume: the dataset already in `out` replaces `data` (it must hold the requested features);
/// returns the files it covers.
std::unordered_set<std::string> ResumeFrom(const fs::path& out, ml::Dataset& data) {
    std::unordered_set<std::string> done;
    ml::Dataset previous = ml::ReadDatasetFile(out);
    if (previous.BlockNames() != data.BlockNames() || previous.cols() != data.cols()) {
        std::string have;
        for (const auto& b : previous.BlockNames()) have += (have.empty() ? "" : ",") + b;
        throw InvalidArgument(fmt::format(
            "--resume: {} holds the features {}, not the requested ones", out.string(), have));
    }
    for (const auto& s : previous.sources) done.insert(FileOfSource(s));
    data = std::move(previous);
    return done;
}

/// Point indices per label value (finite points only; all under label 0 for a whole frame).
std::map<std::uint32_t, Indices> PointsByLabel(const PointCloud& cloud, bool whole) {
    std::map<std::uint32_t, Indices> by_label;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.points[i].allFinite()) continue;
        by_label[whole ? 0u : cloud.labels[i]].push_back(static_cast<Index>(i));
    }
    return by_label;
}

/// The objects to extract from a frame: the manifest's, else the whole frame, else every labelled
/// cluster (label 0 is background) under the file's class.
std::vector<ExtractionObject> ExtractionTargets(const ExtractionInput& input,
                                                const std::map<std::uint32_t, Indices>& by_label,
                                                bool whole) {
    std::vector<ExtractionObject> targets;
    if (!input.objects.empty()) {
        targets = input.objects;
    } else if (whole) {
        targets.push_back({0u, input.class_path, input.group});
    } else {
        for (const auto& [label, idx] : by_label) {
            if (label != 0) targets.push_back({label, input.class_path, input.group});
        }
    }
    return targets;
}

/// One object's row: skipped (and counted) when the cluster is too small or a feature is not
/// finite.
void AddTargetRow(const ExtractionInput& input, const PointCloud& cloud, const Indices& points,
                  const ExtractionObject& t, bool whole, const DatasetExtractionParams& p,
                  DatasetOutput& output, DatasetExtractionSummary& summary) {
    std::optional<std::vector<float>> row;
    try {
        row = ExtractClusterFeatures(SelectByIndex(cloud, points), cloud.sensor_origin, p);
    } catch (...) {
        output.SaveIfDirty();
        throw;
    }
    if (!row) {
        ++summary.small_clusters;
        return;
    }
    if (!std::all_of(row->begin(), row->end(), [](float v) { return std::isfinite(v); })) {
        LogWarning("{} label {}: a feature is not finite, row skipped", input.file.string(),
                   t.label);
        ++summary.bad_features;
        return;
    }
    const std::string source = whole ? input.source : fmt::format("{}#{}", input.source, t.label);
    output.data.AppendRow(*row, t.class_path, t.group, input.view, source);
    ++summary.rows_added;
    output.dirty = true;
}

/// The rows of one frame (with the frame's up direction when it has one); objects not visible in
/// it are skipped.
void ExtractFrame(const ExtractionInput& input, const DatasetExtractionParams& params,
                  DatasetOutput& output, DatasetExtractionSummary& summary) {
    PointCloud cloud;
    try {
        cloud = io::ReadPointCloud(input.file);
    } catch (...) {
        output.SaveIfDirty();
        throw;
    }
    const bool whole = input.objects.empty() && !input.per_cluster;
    if (!whole && !cloud.HasLabels()) {
        output.SaveIfDirty();
        throw DataError(fmt::format("{} has no label field", input.file.string()));
    }
    const std::map<std::uint32_t, Indices> by_label = PointsByLabel(cloud, whole);
    const std::vector<ExtractionObject> targets = ExtractionTargets(input, by_label, whole);
    DatasetExtractionParams p = params;
    if (input.up) p.feature_params.up = *input.up;
    for (const ExtractionObject& t : targets) {
        const auto it = by_label.find(t.label);
        if (it == by_label.end()) continue;  // not visible in this frame
        AddTargetRow(input, cloud, it->second, t, whole, p, output, summary);
    }
}

}  // namespace

std::vector<ExtractionInput> ManifestInputs(const fs::path& manifest) {
    const json m = io::ReadJsonFile(manifest);
    const std::string format = Get<std::string>(m, "format", manifest);
    if (format.rfind("multicue.sim/", 0) != 0) {
        throw FormatError(
            fmt::format("{}: not a simulator manifest (format '{}')", manifest.string(), format));
    }
    if (!m.value("complete", true)) {
        LogWarning("{}: the simulation was interrupted; extracting the scenes it lists",
                   manifest.string());
    }
    const fs::path dir = manifest.parent_path();
    std::vector<ExtractionInput> inputs;
    const json scenes = Get<json>(m, "scenes", manifest);
    if (!scenes.is_array()) {
        throw FormatError(fmt::format("{}: \"scenes\" is not a list", manifest.string()));
    }
    for (const json& scene : scenes) {
        const auto seed = Get<std::uint64_t>(scene, "seed", manifest);
        std::vector<ExtractionObject> objects;
        for (const json& o : Get<json>(scene, "objects", manifest)) {
            const auto label = Get<std::uint32_t>(o, "label", manifest);
            if (label < 20) continue;  // support, floor, walls
            const auto category = Get<std::string>(o, "category", manifest);
            const auto source = Get<std::string>(o, "source", manifest);
            const bool mesh = IsMeshFile(source);
            const std::string kind = mesh ? fs::path(source).stem().string() : source;
            const std::int64_t group = mesh ? StableId("mesh:" + source)
                                            : StableId(fmt::format("proc:{}:{}", seed, label));
            objects.push_back({label, category + "/" + kind, group});
        }
        const json frames = Get<json>(scene, "frames", manifest);
        if (!frames.is_array()) {
            throw FormatError(fmt::format("{}: \"frames\" is not a list", manifest.string()));
        }
        for (std::size_t v = 0; v < frames.size(); ++v) {
            ExtractionInput input;
            input.source = Get<std::string>(frames[v], "file", manifest);
            input.file = dir / input.source;
            input.view = static_cast<std::int64_t>(v);
            const json T = Get<json>(frames[v], "T_world_sensor", manifest);
            if (T.is_array() && T.size() >= 3) {
                // Row 2 of the rotation = world z expressed in the sensor frame.
                Eigen::Vector3f up;
                for (int c = 0; c < 3; ++c) {
                    if (!T[2].is_array() || T[2].size() < 3 || !T[2][c].is_number() ||
                        !(std::abs(T[2][c].get<double>()) <= 1e30)) {
                        throw FormatError(fmt::format("{}: malformed T_world_sensor of {}",
                                                      manifest.string(), input.source));
                    }
                    up[c] = T[2][c].get<float>();
                }
                if (up.norm() > 0.5f) input.up = up.normalized();
            }
            input.objects = objects;
            inputs.push_back(std::move(input));
        }
    }
    return inputs;
}

std::vector<ExtractionInput> TreeInputs(const fs::path& root, bool per_cluster) {
    std::error_code ec;
    if (!fs::is_directory(root, ec)) {
        throw IoError(fmt::format("{} is not a folder", root.string()));
    }
    std::vector<fs::path> files;
    for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::end(it);
         it.increment(ec)) {
        if (!it->is_regular_file()) continue;
        std::string ext = it->path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (ext == ".pcd" || ext == ".ply") files.push_back(it->path());
    }
    if (ec) throw IoError(fmt::format("cannot list {}: {}", root.string(), ec.message()));
    if (files.empty()) {
        throw DataError(fmt::format("{} holds no .pcd or .ply file", root.string()));
    }
    std::sort(files.begin(), files.end());
    std::map<std::string, std::int64_t> views;
    std::vector<ExtractionInput> inputs;
    for (const fs::path& f : files) {
        ExtractionInput input;
        input.file = f;
        input.source = fs::relative(f, root).generic_string();
        input.class_path = ml::LabelPathFromFile(root, f);
        if (input.class_path.empty()) {
            throw DataError(fmt::format("{} lies directly in {}: files need a label folder",
                                        f.string(), root.string()));
        }
        input.group = StableId("folder:" + input.class_path);
        input.view = views[input.class_path]++;
        input.per_cluster = per_cluster;
        inputs.push_back(std::move(input));
    }
    return inputs;
}

ml::Dataset EmptyFeatureDataset(const std::vector<std::string>& features) {
    if (features.empty()) throw InvalidArgument("features: the list is empty");
    std::vector<std::pair<std::string, std::vector<std::string>>> blocks;
    std::set<std::string> seen;
    for (const auto& name : features) {
        const ClusterFeature& f = FindClusterFeature(name);
        if (!seen.insert(name).second) {
            throw InvalidArgument(fmt::format("features: '{}' is listed twice", name));
        }
        std::vector<std::string> columns;
        for (int i = 0; i < f.dimension; ++i) {
            columns.push_back(ml::IndexedName(name, static_cast<std::size_t>(i)));
        }
        blocks.emplace_back(name, std::move(columns));
    }
    return ml::Dataset::WithBlocks(blocks);
}

std::optional<std::vector<float>> ExtractClusterFeatures(const PointCloud& cluster,
                                                         const Eigen::Vector3f& viewpoint,
                                                         const DatasetExtractionParams& params) {
    PointCloud c = params.voxel_size > 0.0f
                       ? VoxelGrid(cluster, {.leaf_size = params.voxel_size,
                                             .num_threads = params.feature_params.num_threads})
                       : cluster;
    if (c.size() < params.min_points) return std::nullopt;
    c.sensor_origin = viewpoint;
    {
        const KdTree tree(c);
        SetNormals(c, EstimateNormals(c, tree,
                                      {.radius = params.normal_radius,
                                       .viewpoint = viewpoint,
                                       .num_threads = params.feature_params.num_threads}));
    }
    // Points without a normal (isolated after downsampling) take no part in the features.
    Indices keep;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (c.points[i].allFinite() && c.normals[i].allFinite())
            keep.push_back(static_cast<Index>(i));
    }
    if (keep.size() < params.min_points) return std::nullopt;
    if (keep.size() < c.size()) c = SelectByIndex(c, keep);
    c.sensor_origin = viewpoint;
    ClusterFeatureParams fp = params.feature_params;
    if (!fp.viewpoint) fp.viewpoint = viewpoint;
    std::vector<float> row;
    for (const auto& name : params.features) {
        const FeatureVector f = ComputeClusterFeature(name, c, fp);
        row.insert(row.end(), f.data(), f.data() + f.size());
    }
    return row;
}

DatasetExtractionSummary ExtractDataset(const std::vector<ExtractionInput>& inputs,
                                        const fs::path& out, const DatasetExtractionParams& params,
                                        Progress& progress) {
    CheckExtractionParams(params);
    DatasetOutput output{EmptyFeatureDataset(params.features), out};
    DatasetExtractionSummary summary;
    summary.files = inputs.size();
    std::unordered_set<std::string> done;
    std::error_code ec;
    if (params.resume && fs::exists(out, ec)) done = ResumeFrom(out, output.data);

    for (const ExtractionInput& input : inputs) {
        if (InterruptRequested()) {
            summary.interrupted = true;
            break;
        }
        if (done.count(input.source) != 0) {
            ++summary.files_resumed;
            progress.Advance();
            continue;
        }
        ExtractFrame(input, params, output, summary);
        ++summary.files_done;
        progress.Advance();
        if (++output.since_save >= params.save_every) output.Save();
    }
    if (output.dirty || !fs::exists(out, ec)) output.Save();
    summary.rows = output.data.rows();
    return summary;
}

}  // namespace multicue
