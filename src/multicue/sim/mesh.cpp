#include "multicue/sim/mesh.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <sstream>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <assimp/Importer.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/ply.hpp"
#include "multicue/sim/assimp_read.hpp"

namespace multicue::sim {
namespace {

std::uint32_t PartIndex(PartMesh& m, const std::string& name) {
    for (std::size_t i = 0; i < m.part_names.size(); ++i) {
        if (m.part_names[i] == name) return static_cast<std::uint32_t>(i);
    }
    m.part_names.push_back(name);
    return static_cast<std::uint32_t>(m.part_names.size() - 1);
}

struct AssimpCollector {
    const aiScene* scene = nullptr;
    float scale = 1.0f;
    PartMesh out;
    bool all_colored = true;
    std::vector<Color> colors;

    void Visit(const aiNode* node, const aiMatrix4x4& parent) {
        const aiMatrix4x4 T = parent * node->mTransformation;
        for (unsigned k = 0; k < node->mNumMeshes; ++k) {
            const aiMesh* mesh = scene->mMeshes[node->mMeshes[k]];
            std::string name = node->mName.C_Str();
            if (name.empty() || node == scene->mRootNode) name = mesh->mName.C_Str();
            if (name.empty()) name = fmt::format("part{}", node->mMeshes[k]);
            AddMesh(mesh, T, name);
        }
        for (unsigned c = 0; c < node->mNumChildren; ++c) Visit(node->mChildren[c], T);
    }

    void AddMesh(const aiMesh* mesh, const aiMatrix4x4& T, const std::string& part) {
        const auto base = static_cast<std::uint32_t>(out.mesh.vertices.size());
        const bool has_color = mesh->HasVertexColors(0);
        all_colored = all_colored && has_color;
        for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
            const aiVector3D p = T * mesh->mVertices[i];
            out.mesh.vertices.emplace_back(p.x * scale, p.y * scale, p.z * scale);
            if (has_color) {
                const aiColor4D c = mesh->mColors[0][i];
                auto to8 = [](float v) {
                    return static_cast<std::uint8_t>(std::clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f);
                };
                colors.push_back(Color{to8(c.r), to8(c.g), to8(c.b), 255});
            } else {
                colors.push_back(Color{});
            }
        }
        std::uint32_t part_index = 0;
        bool part_known = false;
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            if (face.mNumIndices != 3) continue;  // points and lines carry no surface
            if (!part_known) {
                part_index = PartIndex(out, part);
                part_known = true;
            }
            out.mesh.triangles.emplace_back(base + face.mIndices[0], base + face.mIndices[1],
                                            base + face.mIndices[2]);
            out.triangle_parts.push_back(part_index);
        }
    }
};

}  // namespace

std::vector<std::string> SplitCsvLine(const std::string& line) {
    std::vector<std::string> fields;
    std::string field;
    bool quoted = false;
    for (std::size_t i = 0; i < line.size(); ++i) {
        const char c = line[i];
        if (quoted) {
            if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
                field += '"';
                ++i;
            } else if (c == '"') {
                quoted = false;
            } else {
                field += c;
            }
        } else if (c == '"') {
            quoted = true;
        } else if (c == ',') {
            fields.push_back(field);
            field.clear();
        } else if (c != '\r') {
            field += c;
        }
    }
    fields.push_back(field);
    return fields;
}

Eigen::AlignedBox3f PartMesh::Bounds() const {
    Eigen::AlignedBox3f box;
    for (const auto& v : mesh.vertices) box.extend(v);
    return box;
}

void PartMesh::AppendParts(const PartMesh& other) {
    std::vector<std::uint32_t> remap(other.part_names.size());
    for (std::size_t i = 0; i < other.part_names.size(); ++i) {
        remap[i] = PartIndex(*this, other.part_names[i]);
    }
    const bool reflectance = (vertex_reflectance.size() == mesh.vertices.size() || mesh.empty()) &&
                             other.vertex_reflectance.size() == other.mesh.vertices.size();
    mesh.Append(other.mesh);
    if (reflectance) {
        vertex_reflectance.insert(vertex_reflectance.end(), other.vertex_reflectance.begin(),
                                  other.vertex_reflectance.end());
    } else {
        vertex_reflectance.clear();
    }
    for (auto p : other.triangle_parts) triangle_parts.push_back(remap.at(p));
}

void PartMesh::Validate() const {
    mesh.Validate();
    if (triangle_parts.size() != mesh.triangles.size()) {
        throw DataError(fmt::format("mesh '{}': {} part indices for {} triangles", name,
                                    triangle_parts.size(), mesh.triangles.size()));
    }
    if (!vertex_reflectance.empty() && vertex_reflectance.size() != mesh.vertices.size()) {
        throw DataError(fmt::format("mesh '{}': {} reflectances for {} vertices", name,
                                    vertex_reflectance.size(), mesh.vertices.size()));
    }
    for (auto p : triangle_parts) {
        if (p >= part_names.size()) {
            throw DataError(fmt::format("mesh '{}': part index {} out of range", name, p));
        }
    }
}

namespace {

// Whether the file starts like a PLY file ("ply" on its own first line).
bool IsPlyFile(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    char head[5] = {};
    in.read(head, 5);
    const std::string_view h(head, static_cast<std::size_t>(in.gcount()));
    return h.starts_with("ply\n") || h.starts_with("ply\r\n");
}

// PLY meshes are read by multicue's own reader (io/ply.hpp, fuzzed with the other readers), not
// by Assimp: Debian's Assimp crashes on damaged PLY files (a header without end_header, binary
// data that ends early). The mesh is one part, "part0", as Assimp names it; colours keep their
// 8-bit values with an opaque alpha, as through Assimp. Faces with more than three vertices are
// fan-triangulated (the shared PLY meshes have triangles only).
PartMesh ReadPlyPartMesh(const std::filesystem::path& path, float scale) {
    TriangleMesh m = io::ReadPlyMesh(path);
    PartMesh out;
    out.name = path.filename().string();
    out.mesh.vertices.reserve(m.vertices.size());
    for (const auto& v : m.vertices) out.mesh.vertices.push_back(v * scale);
    out.mesh.triangles = std::move(m.triangles);
    if (!m.vertex_colors.empty() && m.vertex_colors.size() == m.vertices.size()) {
        out.mesh.vertex_colors = std::move(m.vertex_colors);
        for (auto& c : out.mesh.vertex_colors) c.a = 255;
    }
    if (!out.mesh.triangles.empty()) out.part_names = {"part0"};
    out.triangle_parts.assign(out.mesh.triangles.size(), 0);
    return out;
}

// Debian's Assimp crashes on damaged COLLADA files (accessors that count more values than their
// arrays hold), and none of the mesh libraries uses COLLADA: it is refused, by its extension and
// by its content, whatever the file is called.
void RefuseCollada(const std::filesystem::path& path) {
    const std::string ext = io::LowerExtension(path);
    std::ifstream in(path, std::ios::binary);
    std::string head(4096, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
    if (ext == "dae" || ext == "zae" || head.find("<COLLADA") != std::string::npos) {
        throw FormatError(fmt::format(
            "{}: COLLADA meshes are not read; convert the mesh to OBJ or PLY", path.string()));
    }
}

}  // namespace

PartMesh LoadMesh(const std::filesystem::path& path, const MeshLoadParams& params) {
    if (!(params.scale > 0.0f) || !std::isfinite(params.scale)) {
        throw InvalidArgument(fmt::format("mesh scale must be > 0, got {}", params.scale));
    }
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        throw IoError(fmt::format("{}: no such mesh file", path.string()));
    }
    PartMesh out;
    if (io::LowerExtension(path) == "ply" || IsPlyFile(path)) {
        out = ReadPlyPartMesh(path, params.scale);
    } else {
        RefuseCollada(path);
        Assimp::Importer importer;
        // No vertex joining: OBJ files already share vertices, and joining would merge parts.
        // The scene is validated (indices within the vertices, counts matching arrays) before
        // any other step reads it, and refused when broken.
        const aiScene* scene = assimp_read::ReadScene(
            importer, path,
            aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_FindInvalidData);
        AssimpCollector collector;
        collector.scene = scene;
        collector.scale = params.scale;
        collector.out.name = path.filename().string();
        collector.Visit(scene->mRootNode, aiMatrix4x4());
        out = std::move(collector.out);
        if (collector.all_colored) out.mesh.vertex_colors = std::move(collector.colors);
    }
    if (out.mesh.triangles.empty()) {
        throw DataError(fmt::format("{}: mesh has no triangles", path.string()));
    }
    for (const auto& v : out.mesh.vertices) {
        if (!v.allFinite()) throw DataError(fmt::format("{}: non-finite vertex", path.string()));
    }
    const float extent = out.Bounds().sizes().maxCoeff();
    if (extent > params.max_extent || extent < params.min_extent) {
        throw DataError(fmt::format(
            "{}: largest extent {:.4g} m after scale {} is outside [{}, {}] m (wrong units?)",
            path.string(), extent, params.scale, params.min_extent, params.max_extent));
    }
    out.Validate();
    return out;
}

std::optional<PartMesh> TryLoadMesh(const std::filesystem::path& path, const MeshLoadParams& params,
                                    bool strict) {
    try {
        return LoadMesh(path, params);
    } catch (const InvalidArgument&) {
        throw;
    } catch (const Error& e) {
        if (strict) throw;
        LogWarning("skipping mesh: {}", e.what());
        return std::nullopt;
    }
}

const std::vector<std::string>& CategoryNames() {
    static const std::vector<std::string> names = {"none",     "sphere",  "box",      "flat",
                                                   "cylinder", "plate",   "other",    "table",
                                                   "chair",    "cabinet", "sideboard"};
    return names;
}

int CategoryIndex(const std::string& name) {
    const auto& names = CategoryNames();
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

const std::vector<std::string>& TabletopCategories() {
    static const std::vector<std::string> names = {"sphere",   "box",   "flat",
                                                   "cylinder", "plate", "other"};
    return names;
}

const std::vector<std::string>& FurnitureCategories() {
    static const std::vector<std::string> names = {"table", "chair", "cabinet", "sideboard"};
    return names;
}

std::pair<float, float> RealisticExtentRange(const std::string& category) {
    static const std::map<std::string, std::pair<float, float>> ranges = {
        {"sphere", {0.06f, 0.25f}},   {"box", {0.08f, 0.25f}},   {"flat", {0.14f, 0.35f}},
        {"cylinder", {0.07f, 0.30f}}, {"plate", {0.16f, 0.30f}}, {"other", {0.10f, 0.30f}}};
    const auto it = ranges.find(category);
    if (it == ranges.end()) {
        throw InvalidArgument(fmt::format("no realistic size range for category '{}'", category));
    }
    return it->second;
}

std::vector<MeshEntry> ReadMeshLibrary(const std::filesystem::path& folder,
                                       const std::vector<std::string>& categories,
                                       const std::filesystem::path& labels) {
    const auto csv = labels.empty() ? folder / "labels.csv" : labels;
    std::ifstream in(csv);
    if (!in) throw IoError(fmt::format("{}: cannot open mesh library labels", csv.string()));
    std::vector<std::string> allowed = categories;
    if (allowed.empty()) allowed.assign(CategoryNames().begin() + 1, CategoryNames().end());

    std::string line;
    if (!std::getline(in, line)) throw FormatError(fmt::format("{}: empty file", csv.string()));
    const auto header = SplitCsvLine(line);
    auto column = [&](const char* name) {
        const auto it = std::find(header.begin(), header.end(), name);
        return it == header.end() ? -1 : static_cast<int>(it - header.begin());
    };
    const int c_file = column("file"), c_cat = column("category"), c_scale = column("scale_to_m");
    const int c_source = column("source"), c_object = column("object");
    if (c_file < 0 || c_cat < 0) {
        throw FormatError(
            fmt::format("{}:1: header needs 'file' and 'category' columns", csv.string()));
    }
    std::vector<MeshEntry> entries;
    for (int line_no = 2; std::getline(in, line); ++line_no) {
        if (line.empty() || line == "\r") continue;
        const auto f = SplitCsvLine(line);
        const auto where = fmt::format("{}:{}", csv.string(), line_no);
        auto get = [&](int c) -> std::string {
            if (c < 0) return {};
            if (c >= static_cast<int>(f.size())) {
                throw FormatError(
                    fmt::format("{}: {} fields, expected {}", where, f.size(), header.size()));
            }
            return f[static_cast<std::size_t>(c)];
        };
        MeshEntry e;
        const std::string file = get(c_file);
        e.file = folder / file;
        e.category = get(c_cat);
        if (file.empty()) throw FormatError(fmt::format("{}: empty file name", where));
        if (std::find(allowed.begin(), allowed.end(), e.category) == allowed.end()) {
            throw FormatError(
                fmt::format("{}: unknown category '{}' for {}", where, e.category, file));
        }
        std::error_code ec;
        if (!std::filesystem::is_regular_file(e.file, ec)) {
            throw FormatError(
                fmt::format("{}: mesh file {} does not exist", where, e.file.string()));
        }
        const std::string scale = get(c_scale);
        if (!scale.empty()) {
            char* end = nullptr;
            e.scale_to_m = std::strtof(scale.c_str(), &end);
            if (end == scale.c_str() || *end != '\0' || !(e.scale_to_m > 0.0f) ||
                !std::isfinite(e.scale_to_m)) {
                throw FormatError(fmt::format("{}: bad scale_to_m '{}'", where, scale));
            }
        }
        const auto stem = e.file.stem().string();
        const auto sep = stem.find("__");
        e.source = get(c_source);
        if (e.source.empty() && sep != std::string::npos) e.source = stem.substr(0, sep);
        e.object = get(c_object);
        if (e.object.empty()) e.object = sep != std::string::npos ? stem.substr(sep + 2) : stem;
        e.rescale = e.source == "kit";
        entries.push_back(std::move(e));
    }
    return entries;
}

}  // namespace multicue::sim
