#include "multicue/ml/dataset.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "multicue/core/exceptions.hpp"
#include "multicue/ml/serialization.hpp"

namespace multicue::ml {

namespace {
constexpr std::string_view kDatasetMagic = "MCUEDSET";
}

Dataset Dataset::WithBlocks(
    const std::vector<std::pair<std::string, std::vector<std::string>>>& blocks) {
    Dataset d;
    for (const auto& [name, cols] : blocks) {
        if (name.empty()) throw InvalidArgument("feature block name must not be empty");
        d.blocks.push_back({name, d.num_cols, cols.size()});
        d.feature_names.insert(d.feature_names.end(), cols.begin(), cols.end());
        d.num_cols += cols.size();
    }
    return d;
}

Dataset Dataset::WithColumns(std::size_t cols, const std::string& block) {
    std::vector<std::string> names(cols);
    for (std::size_t i = 0; i < cols; ++i) {
        names[i] = IndexedName("f", i);
    }
    return WithBlocks({{block, names}});
}

int Dataset::ClassId(const std::string& path) {
    if (path.empty()) return kNoLabel;
    const int id = FindClass(path);
    if (id != kNoLabel) return id;
    class_names.push_back(path);
    return static_cast<int>(class_names.size()) - 1;
}

int Dataset::FindClass(const std::string& path) const {
    const auto it = std::find(class_names.begin(), class_names.end(), path);
    return it == class_names.end() ? kNoLabel : static_cast<int>(it - class_names.begin());
}

void Dataset::AppendRow(std::span<const float> features, const std::string& label,
                        std::int64_t group, std::int64_t view, std::string source,
                        std::int64_t row_id) {
    if (features.size() != num_cols) {
        throw InvalidArgument("row has " + std::to_string(features.size()) +
                              " features, the dataset has " + std::to_string(num_cols) +
                              " columns");
    }
    for (std::size_t c = 0; c < features.size(); ++c) {
        if (!std::isfinite(features[c])) {
            throw DataError("non-finite value in column '" + feature_names[c] + "' of a new row");
        }
    }
    values.insert(values.end(), features.begin(), features.end());
    labels.push_back(ClassId(label));
    groups.push_back(group);
    views.push_back(view);
    std::int64_t id = row_id;
    if (id < 0) id = row_ids.empty() ? 0 : row_ids.back() + 1;
    row_ids.push_back(id);
    sources.push_back(std::move(source));
}

std::vector<std::size_t> Dataset::ClassCounts() const {
    std::vector<std::size_t> counts(num_classes(), 0);
    for (const int l : labels) {
        if (l >= 0 && static_cast<std::size_t>(l) < counts.size()) {
            ++counts[static_cast<std::size_t>(l)];
        }
    }
    return counts;
}

std::unordered_set<std::string> Dataset::Sources() const {
    return {sources.begin(), sources.end()};
}

std::size_t Dataset::BlockIndex(const std::string& name) const {
    for (std::size_t i = 0; i < blocks.size(); ++i) {
        if (blocks[i].name == name) return i;
    }
    std::string known;
    for (const auto& b : blocks) {
        if (!known.empty()) known += ", ";
        known += b.name;
    }
    throw InvalidArgument("no feature block '" + name + "' (blocks: " + known + ")");
}

std::vector<std::string> Dataset::BlockNames() const {
    std::vector<std::string> names;
    for (const auto& b : blocks) names.push_back(b.name);
    return names;
}

void Dataset::Validate(const std::string& what) const {
    const std::size_t n = labels.size();
    auto fail = [&](const std::string& m) { throw FormatError(what + ": " + m); };
    if (values.size() != n * num_cols) fail("feature values do not match rows x columns");
    if (groups.size() != n || views.size() != n || row_ids.size() != n || sources.size() != n) {
        fail("per-row fields have different lengths");
    }
    if (feature_names.size() != num_cols) fail("feature name count differs from column count");
    std::size_t next = 0;
    for (const auto& b : blocks) {
        if (b.begin != next || b.count == 0) fail("feature blocks do not tile the columns");
        next += b.count;
    }
    if (next != num_cols) fail("feature blocks do not cover all columns");
    for (int l : labels) {
        if (l != kNoLabel && (l < 0 || l >= static_cast<int>(class_names.size()))) {
            fail("label id " + std::to_string(l) + " out of range");
        }
    }
    std::unordered_set<std::int64_t> ids(row_ids.begin(), row_ids.end());
    if (ids.size() != n) fail("row ids are not unique");
}

void Dataset::CheckFinite(const std::string& what) const {
    for (std::size_t i = 0; i < values.size(); ++i) {
        if (!std::isfinite(values[i])) {
            const std::size_t r = i / num_cols, c = i % num_cols;
            throw DataError(what + ": non-finite value in row " + std::to_string(r) + ", column '" +
                            feature_names[c] + "'");
        }
    }
}

std::string LabelPathFromFile(const std::filesystem::path& root,
                              const std::filesystem::path& file) {
    const auto rel = file.lexically_normal().lexically_relative(root.lexically_normal());
    if (rel.empty() || *rel.begin() == "..") {
        throw InvalidArgument(file.string() + " is not below " + root.string());
    }
    std::string label;
    for (const auto& part : rel.parent_path()) {
        if (part == ".") continue;
        if (!label.empty()) label += '/';
        label += part.string();
    }
    return label;
}

std::string IndexedName(std::string_view prefix, std::size_t index) {
    std::string s(prefix);
    s.append(std::to_string(index));
    return s;
}

std::string TruncateLabelPath(const std::string& path, std::size_t depth) {
    if (depth == 0) return path;
    std::size_t pos = 0;
    for (std::size_t d = 0; d < depth; ++d) {
        pos = path.find('/', pos);
        if (pos == std::string::npos) return path;
        if (d + 1 < depth) ++pos;
    }
    return path.substr(0, pos);
}

// Payload of format version 1, in this order: num_rows u64, num_cols u64, feature names,
// blocks (count, then name/begin/count), class names, values f32[], labels i32[], groups i64[],
// views i64[], row ids i64[], sources.
void SaveDataset(const Dataset& data, const std::filesystem::path& path) {
    data.Validate(path.string());
    ByteWriter w;
    w.Put<std::uint64_t>(data.rows());
    w.Put<std::uint64_t>(data.num_cols);
    w.PutStrings(data.feature_names);
    w.Put<std::uint64_t>(data.blocks.size());
    for (const auto& b : data.blocks) {
        w.PutString(b.name);
        w.Put<std::uint64_t>(b.begin);
        w.Put<std::uint64_t>(b.count);
    }
    w.PutStrings(data.class_names);
    w.PutVector(data.values);
    w.PutVector(data.labels);
    w.PutVector(data.groups);
    w.PutVector(data.views);
    w.PutVector(data.row_ids);
    w.PutStrings(data.sources);
    WriteContainer(path, kDatasetMagic, kDatasetFormatVersion, w.bytes());
}

Dataset LoadDataset(const std::filesystem::path& path) {
    const std::string payload =
        ReadContainer(path, kDatasetMagic, kDatasetFormatVersion, "dataset");
    ByteReader r(payload, path.string());
    Dataset d;
    const auto rows = r.Get<std::uint64_t>();
    d.num_cols = r.Get<std::uint64_t>();
    d.feature_names = r.GetStrings();
    const auto nblocks = r.Get<std::uint64_t>();
    if (nblocks > d.num_cols) r.Fail("bad block count");
    for (std::uint64_t i = 0; i < nblocks; ++i) {
        FeatureBlock b;
        b.name = r.GetString();
        b.begin = r.Get<std::uint64_t>();
        b.count = r.Get<std::uint64_t>();
        d.blocks.push_back(b);
    }
    d.class_names = r.GetStrings();
    d.values = r.GetVector<float>();
    d.labels = r.GetVector<int>();
    d.groups = r.GetVector<std::int64_t>();
    d.views = r.GetVector<std::int64_t>();
    d.row_ids = r.GetVector<std::int64_t>();
    d.sources = r.GetStrings();
    if (!r.AtEnd()) r.Fail("trailing bytes in payload");
    if (d.labels.size() != rows) r.Fail("row count mismatch");
    d.Validate(path.string());
    return d;
}

Dataset ReadDatasetFile(const std::filesystem::path& path) {
    auto ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    return ext == ".csv" ? LoadCsv(path) : LoadDataset(path);
}

void WriteDatasetFile(const Dataset& data, const std::filesystem::path& path) {
    auto ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".csv") {
        SaveCsv(data, path);
    } else {
        SaveDataset(data, path);
    }
}

}  // namespace multicue::ml
