// CSV import and export of datasets (section 3.1.4: ASCII serialization).

#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "multicue/core/exceptions.hpp"
#include "multicue/ml/dataset.hpp"
#include "multicue/ml/serialization.hpp"

namespace multicue::ml {

namespace {

std::string Quote(const std::string& s) {
    if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
    std::string q = "\"";
    for (char c : s) {
        if (c == '"') q += '"';
        q += c;
    }
    return q + "\"";
}

// Splits one CSV record (RFC 4180 quoting, no embedded newlines).
std::vector<std::string> SplitRecord(const std::string& line, const std::string& where) {
    std::vector<std::string> out;
    std::string cur;
    bool quoted = false;
    for (std::size_t i = 0; i < line.size(); ++i) {
        const char c = line[i];
        if (quoted) {
            if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
                cur += '"';
                ++i;
            } else if (c == '"') {
                quoted = false;
            } else {
                cur += c;
            }
        } else if (c == '"') {
            quoted = true;
        } else if (c == ',') {
            out.push_back(std::move(cur));
            cur.clear();
        } else if (c != '\r') {
            cur += c;
        }
    }
    if (quoted) throw FormatError(where + ": unterminated quote");
    out.push_back(std::move(cur));
    return out;
}

template <typename T>
T ParseNumber(const std::string& s, const std::string& where) {
    T v{};
    const char* end = s.data() + s.size();
    auto [p, ec] = std::from_chars(s.data(), end, v);
    if (ec != std::errc() || p != end) throw FormatError(where + ": not a number: '" + s + "'");
    return v;
}

float ParseFloat(const std::string& s, const std::string& where) {
    // from_chars for float accepts "nan"/"inf", which CheckFinite rejects with a clear message.
    return ParseNumber<float>(s, where);
}

}  // namespace

void SaveCsv(const Dataset& data, const std::filesystem::path& path) {
    data.Validate(path.string());
    std::ostringstream out;
    out << "row_id,group,view,label,source";
    for (const auto& b : data.blocks) {
        for (std::size_t c = b.begin; c < b.begin + b.count; ++c) {
            out << ',' << Quote(b.name + ":" + data.feature_names[c]);
        }
    }
    out << '\n';
    char buf[32];
    for (std::size_t r = 0; r < data.rows(); ++r) {
        const int l = data.labels[r];
        out << data.row_ids[r] << ',' << data.groups[r] << ',' << data.views[r] << ','
            << Quote(l == kNoLabel ? "" : data.class_names[l]) << ',' << Quote(data.sources[r]);
        for (float v : data.row(r)) {
            std::snprintf(buf, sizeof(buf), "%.9g", static_cast<double>(v));
            out << ',' << buf;
        }
        out << '\n';
    }
    WriteBytesAtomically(path, out.str());
}

Dataset LoadCsv(const std::filesystem::path& path) {
    const std::string text = ReadBytes(path);
    std::istringstream in(text);
    std::string line;
    const std::string name = path.string();
    if (!std::getline(in, line)) throw FormatError(name + ": empty CSV file (no header)");
    const auto header = SplitRecord(line, name + ":1");
    enum Meta { kRowId, kGroup, kView, kLabel, kSource };
    const std::map<std::string, Meta> meta_names = {{"row_id", kRowId},
                                                    {"group", kGroup},
                                                    {"view", kView},
                                                    {"label", kLabel},
                                                    {"source", kSource}};
    std::vector<int> meta_of(header.size(), -1);
    std::vector<std::size_t> feature_cols;
    std::vector<std::pair<std::string, std::vector<std::string>>> blocks;
    for (std::size_t i = 0; i < header.size(); ++i) {
        const auto it = meta_names.find(header[i]);
        if (it != meta_names.end()) {
            meta_of[i] = it->second;
            continue;
        }
        const auto colon = header[i].find(':');
        std::string block = colon == std::string::npos ? "features" : header[i].substr(0, colon);
        std::string feat = colon == std::string::npos ? header[i] : header[i].substr(colon + 1);
        if (block.empty()) block = "features";
        if (blocks.empty() || blocks.back().first != block) blocks.push_back({block, {}});
        blocks.back().second.push_back(feat);
        feature_cols.push_back(i);
    }
    std::map<std::string, int> seen_blocks;
    for (const auto& b : blocks) {
        if (seen_blocks[b.first]++ > 0) {
            throw FormatError(name + ": columns of block '" + b.first + "' are not contiguous");
        }
    }
    Dataset d = Dataset::WithBlocks(blocks);
    std::vector<float> row(feature_cols.size());
    std::size_t line_no = 1;
    bool has_ids = false;
    for (int m : meta_of) has_ids |= m == kRowId;
    while (std::getline(in, line)) {
        ++line_no;
        if (line.empty() || line == "\r") continue;
        const std::string where = name + ":" + std::to_string(line_no);
        const auto fields = SplitRecord(line, where);
        if (fields.size() != header.size()) {
            throw FormatError(where + ": " + std::to_string(fields.size()) +
                              " fields, header has " + std::to_string(header.size()));
        }
        std::int64_t id = -1, group = -1, view = -1;
        std::string label, source;
        for (std::size_t i = 0; i < fields.size(); ++i) {
            switch (meta_of[i]) {
                case kRowId:
                    id = ParseNumber<std::int64_t>(fields[i], where);
                    break;
                case kGroup:
                    group = ParseNumber<std::int64_t>(fields[i], where);
                    break;
                case kView:
                    view = ParseNumber<std::int64_t>(fields[i], where);
                    break;
                case kLabel:
                    label = fields[i];
                    break;
                case kSource:
                    source = fields[i];
                    break;
                default:
                    break;
            }
        }
        for (std::size_t k = 0; k < feature_cols.size(); ++k) {
            row[k] = ParseFloat(fields[feature_cols[k]], where);
            if (!std::isfinite(row[k])) {
                throw DataError(where + ": non-finite value in column '" + header[feature_cols[k]] +
                                "'");
            }
        }
        d.AppendRow(row, label, group, view, source, has_ids ? id : -1);
    }
    d.Validate(name);
    return d;
}

}  // namespace multicue::ml
