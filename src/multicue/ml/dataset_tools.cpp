#include "multicue/ml/dataset_tools.hpp"

#include <algorithm>
#include <set>
#include <unordered_map>

#include "multicue/core/exceptions.hpp"

namespace multicue::ml {

namespace {

// Copies the per-row fields of row `r` of `src` into `dst` (class ids stay valid because dst
// shares src's class names).
void CopyRowMeta(const Dataset& src, std::size_t r, Dataset& dst) {
    dst.labels.push_back(src.labels[r]);
    dst.groups.push_back(src.groups[r]);
    dst.views.push_back(src.views[r]);
    dst.row_ids.push_back(src.row_ids[r]);
    dst.sources.push_back(src.sources[r]);
}

Dataset EmptyLike(const Dataset& d) {
    Dataset out;
    out.num_cols = d.num_cols;
    out.feature_names = d.feature_names;
    out.blocks = d.blocks;
    out.class_names = d.class_names;
    return out;
}

}  // namespace

Dataset SelectRows(const Dataset& data, const std::vector<std::size_t>& indices) {
    Dataset out = EmptyLike(data);
    out.values.reserve(indices.size() * data.num_cols);
    for (std::size_t r : indices) {
        if (r >= data.rows()) {
            throw InvalidArgument("row index " + std::to_string(r) + " out of range (" +
                                  std::to_string(data.rows()) + " rows)");
        }
        const auto row = data.row(r);
        out.values.insert(out.values.end(), row.begin(), row.end());
        CopyRowMeta(data, r, out);
    }
    return out;
}

Dataset SelectColumns(const Dataset& data, const std::vector<std::size_t>& columns) {
    // Block of every column.
    std::vector<std::size_t> block_of(data.num_cols);
    for (std::size_t b = 0; b < data.blocks.size(); ++b) {
        for (std::size_t c = 0; c < data.blocks[b].count; ++c)
            block_of[data.blocks[b].begin + c] = b;
    }
    Dataset out;
    out.class_names = data.class_names;
    std::size_t prev_block = SIZE_MAX;
    for (std::size_t c : columns) {
        if (c >= data.num_cols) {
            throw InvalidArgument("column " + std::to_string(c) + " out of range (" +
                                  std::to_string(data.num_cols) + " columns)");
        }
        if (block_of[c] != prev_block) {
            out.blocks.push_back({data.blocks[block_of[c]].name, out.num_cols, 0});
            prev_block = block_of[c];
        }
        ++out.blocks.back().count;
        out.feature_names.push_back(data.feature_names[c]);
        ++out.num_cols;
    }
    std::set<std::string> names;
    for (const auto& b : out.blocks) {
        if (!names.insert(b.name).second) {
            throw InvalidArgument("selection splits block '" + b.name + "' into separate runs");
        }
    }
    out.values.resize(data.rows() * out.num_cols);
    for (std::size_t r = 0; r < data.rows(); ++r) {
        const float* src = data.values.data() + r * data.num_cols;
        float* dst = out.values.data() + r * out.num_cols;
        for (std::size_t k = 0; k < columns.size(); ++k) dst[k] = src[columns[k]];
        CopyRowMeta(data, r, out);
    }
    return out;
}

Dataset SelectBlocks(const Dataset& data, const std::vector<std::string>& blocks) {
    std::vector<std::size_t> cols;
    std::set<std::string> seen;
    for (const auto& name : blocks) {
        if (!seen.insert(name).second) throw InvalidArgument("block '" + name + "' given twice");
        const auto& b = data.blocks[data.BlockIndex(name)];
        for (std::size_t c = 0; c < b.count; ++c) cols.push_back(b.begin + c);
    }
    return SelectColumns(data, cols);
}

Dataset DropBlocks(const Dataset& data, const std::vector<std::string>& blocks) {
    std::set<std::string> drop;
    for (const auto& name : blocks) drop.insert(data.blocks[data.BlockIndex(name)].name);
    std::vector<std::string> keep;
    for (const auto& b : data.blocks) {
        if (!drop.count(b.name)) keep.push_back(b.name);
    }
    return SelectBlocks(data, keep);
}

Dataset DropColumns(const Dataset& data, const std::vector<std::size_t>& columns) {
    std::vector<bool> drop(data.num_cols, false);
    for (std::size_t c : columns) {
        if (c >= data.num_cols)
            throw InvalidArgument("column " + std::to_string(c) + " out of range");
        drop[c] = true;
    }
    std::vector<std::size_t> keep;
    for (std::size_t c = 0; c < data.num_cols; ++c) {
        if (!drop[c]) keep.push_back(c);
    }
    return SelectColumns(data, keep);
}

Dataset ConcatColumns(const Dataset& a, const Dataset& b, bool drop_unmatched) {
    for (const auto& bb : b.blocks) {
        for (const auto& ab : a.blocks) {
            if (ab.name == bb.name) {
                throw InvalidArgument("both datasets have a feature block '" + ab.name + "'");
            }
        }
    }
    std::unordered_map<std::int64_t, std::size_t> row_of_b;
    for (std::size_t r = 0; r < b.rows(); ++r) row_of_b.emplace(b.row_ids[r], r);
    Dataset out;
    out.class_names = a.class_names;
    out.feature_names = a.feature_names;
    out.feature_names.insert(out.feature_names.end(), b.feature_names.begin(),
                             b.feature_names.end());
    out.blocks = a.blocks;
    for (auto bb : b.blocks) {
        bb.begin += a.num_cols;
        out.blocks.push_back(bb);
    }
    out.num_cols = a.num_cols + b.num_cols;
    for (std::size_t r = 0; r < a.rows(); ++r) {
        const auto it = row_of_b.find(a.row_ids[r]);
        if (it == row_of_b.end()) {
            if (drop_unmatched) continue;
            throw DataError("row id " + std::to_string(a.row_ids[r]) +
                            " of the first dataset is missing in the second");
        }
        const std::size_t rb = it->second;
        const std::string la = a.labels[r] == kNoLabel ? "" : a.class_names[a.labels[r]];
        const std::string lb = b.labels[rb] == kNoLabel ? "" : b.class_names[b.labels[rb]];
        if (la != lb || a.groups[r] != b.groups[rb]) {
            throw DataError("row id " + std::to_string(a.row_ids[r]) +
                            " has different labels or groups in the two datasets ('" + la +
                            "' vs '" + lb + "')");
        }
        const auto ra = a.row(r), rbv = b.row(rb);
        out.values.insert(out.values.end(), ra.begin(), ra.end());
        out.values.insert(out.values.end(), rbv.begin(), rbv.end());
        CopyRowMeta(a, r, out);
    }
    return out;
}

Dataset ConcatRows(const Dataset& a, const Dataset& b, bool renumber) {
    if (a.feature_names != b.feature_names || a.BlockNames() != b.BlockNames()) {
        throw InvalidArgument("datasets have different columns (" + std::to_string(a.num_cols) +
                              " vs " + std::to_string(b.num_cols) +
                              " columns or other names/blocks)");
    }
    Dataset out = a;
    std::unordered_map<std::int64_t, bool> ids;
    std::int64_t max_id = -1;
    for (auto id : a.row_ids) {
        ids[id] = true;
        max_id = std::max(max_id, id);
    }
    bool collide = false;
    for (auto id : b.row_ids) collide |= ids.count(id) > 0;
    if (collide && !renumber) throw DataError("row ids of the two datasets collide");
    out.values.insert(out.values.end(), b.values.begin(), b.values.end());
    for (std::size_t r = 0; r < b.rows(); ++r) {
        out.labels.push_back(b.labels[r] == kNoLabel ? kNoLabel
                                                     : out.ClassId(b.class_names[b.labels[r]]));
        out.groups.push_back(b.groups[r]);
        out.views.push_back(b.views[r]);
        out.row_ids.push_back(collide ? ++max_id : b.row_ids[r]);
        out.sources.push_back(b.sources[r]);
    }
    return out;
}

Dataset CompactClasses(const Dataset& data) {
    std::vector<int> remap(data.class_names.size(), kNoLabel);
    Dataset out = data;
    out.class_names.clear();
    for (std::size_t c = 0; c < data.class_names.size(); ++c) {
        if (std::find(data.labels.begin(), data.labels.end(), static_cast<int>(c)) !=
            data.labels.end()) {
            remap[c] = static_cast<int>(out.class_names.size());
            out.class_names.push_back(data.class_names[c]);
        }
    }
    for (auto& l : out.labels) {
        if (l != kNoLabel) l = remap[l];
    }
    return out;
}

Dataset Relabel(const Dataset& data, const std::map<std::string, std::string>& mapping) {
    Dataset out = data;
    out.class_names.clear();
    std::vector<int> remap(data.class_names.size());
    for (std::size_t c = 0; c < data.class_names.size(); ++c) {
        const auto it = mapping.find(data.class_names[c]);
        remap[c] = out.ClassId(it == mapping.end() ? data.class_names[c] : it->second);
    }
    for (auto& l : out.labels) {
        if (l != kNoLabel) l = remap[l];
    }
    return CompactClasses(out);
}

Dataset FlattenLabels(const Dataset& data, std::size_t depth) {
    if (depth == 0) throw InvalidArgument("depth must be >= 1, got 0");
    std::map<std::string, std::string> mapping;
    for (const auto& c : data.class_names) mapping[c] = TruncateLabelPath(c, depth);
    return Relabel(data, mapping);
}

std::vector<int> MapLabels(const Dataset& data, const std::vector<std::string>& class_names) {
    std::vector<int> remap(data.class_names.size());
    for (std::size_t c = 0; c < data.class_names.size(); ++c) {
        const auto it = std::find(class_names.begin(), class_names.end(), data.class_names[c]);
        remap[c] = it == class_names.end() ? kNoLabel : static_cast<int>(it - class_names.begin());
    }
    std::vector<int> out(data.rows());
    for (std::size_t r = 0; r < data.rows(); ++r) {
        const int l = data.labels[r];
        if (l == kNoLabel) {
            out[r] = kNoLabel;
            continue;
        }
        if (remap[l] == kNoLabel) {
            throw DataError("label '" + data.class_names[l] + "' (row " + std::to_string(r) +
                            ") was not seen in training");
        }
        out[r] = remap[l];
    }
    return out;
}

Dataset ConfidencesToDataset(const FeatureMatrix& confidences,
                             const std::vector<std::string>& class_names, const Dataset& rows_of,
                             const std::string& block) {
    if (static_cast<std::size_t>(confidences.rows()) != rows_of.rows() ||
        static_cast<std::size_t>(confidences.cols()) != class_names.size()) {
        throw InvalidArgument("confidence table is " + std::to_string(confidences.rows()) + "x" +
                              std::to_string(confidences.cols()) + ", expected " +
                              std::to_string(rows_of.rows()) + "x" +
                              std::to_string(class_names.size()));
    }
    Dataset out = Dataset::WithBlocks({{block, class_names}});
    out.class_names = rows_of.class_names;
    out.values.assign(confidences.data(), confidences.data() + confidences.size());
    out.labels = rows_of.labels;
    out.groups = rows_of.groups;
    out.views = rows_of.views;
    out.row_ids = rows_of.row_ids;
    out.sources = rows_of.sources;
    return out;
}

}  // namespace multicue::ml
