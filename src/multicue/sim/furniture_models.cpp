#include "multicue/sim/furniture_models.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/articulated.hpp"
#include "multicue/sim/kitchen_library.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/sim_math_internal.hpp"

namespace multicue::sim {
namespace {

using math_internal::kPi;

// The furniture category of a kitchen model kind; empty for kinds that are no furniture here.
std::string KitchenFurnitureCategory(const std::string& kind) {
    if (kind == "table") return "table";
    if (kind == "cupboard" || kind == "sink_cupboard") return "cabinet";
    if (kind == "drawer_unit") return "sideboard";
    return {};
}

std::string AfterLast(const std::string& s, char c) {
    const auto p = s.rfind(c);
    return p == std::string::npos ? s : s.substr(p + 1);
}

bool StartsWith(const std::string& s, const std::string& prefix) {
    return s.compare(0, prefix.size(), prefix) == 0;
}

// Area-weighted centroid of the triangles whose part name starts with one of `prefixes`
// (all triangles when empty) and whose centroid passes `keep`; false when there are none.
template <typename Keep>
bool AreaCentroid(const PartMesh& m, const std::vector<std::string>& prefixes, Keep keep,
                  Eigen::Vector3f& out) {
    double area = 0.0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (std::size_t t = 0; t < m.mesh.triangles.size(); ++t) {
        const std::string& name = m.part_names[m.triangle_parts[t]];
        bool match = prefixes.empty();
        for (const auto& p : prefixes) match = match || StartsWith(name, p);
        if (!match) continue;
        const auto& tri = m.mesh.triangles[t];
        const Eigen::Vector3f a = m.mesh.vertices[tri[0]], b = m.mesh.vertices[tri[1]],
                              c = m.mesh.vertices[tri[2]];
        const Eigen::Vector3f centroid = (a + b + c) / 3.0f;
        if (!keep(centroid)) continue;
        const double s = 0.5 * static_cast<double>((b - a).cross(c - a).norm());
        area += s;
        sum += s * centroid.cast<double>();
    }
    if (area <= 0.0) return false;
    out = (sum / area).cast<float>();
    return true;
}

bool AreaCentroid(const PartMesh& m, const std::vector<std::string>& prefixes,
                  Eigen::Vector3f& out) {
    return AreaCentroid(
        m, prefixes, [](const Eigen::Vector3f&) { return true; }, out);
}

// Rotates `m` about z by `yaw`, then moves it so that its footprint's box is centred on the
// origin and its lowest vertex lies on z = 0.
void Canonicalise(PartMesh& m, float yaw) {
    const Eigen::Matrix3f R = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    for (auto& v : m.mesh.vertices) v = R * v;
    for (auto& n : m.mesh.vertex_normals) n = R * n;
    const Eigen::AlignedBox3f box = m.Bounds();
    const Eigen::Vector3f shift(-box.center().x(), -box.center().y(), -box.min().z());
    for (auto& v : m.mesh.vertices) v += shift;
}

// The yaw that turns the horizontal direction `front` onto +x, snapped to a multiple of 90
// degrees (library models are modelled along their axes).
float SnappedYaw(const Eigen::Vector3f& front) {
    const float a = std::atan2(front.y(), front.x());
    return -std::round(a / (kPi / 2)) * (kPi / 2);
}

// The front of a furniture OBJ file from its named parts (see LoadFurniturePiece); +x when the
// parts do not tell.
float FrontYaw(const PartMesh& m, const std::string& category) {
    const Eigen::AlignedBox3f box = m.Bounds();
    const Eigen::Vector3f centre = box.center();
    Eigen::Vector3f a, b;
    if (category == "chair") {
        Eigen::Vector3f seat;
        if (!AreaCentroid(m, {"seat"}, seat)) return 0.0f;
        float seat_top = -1e9f;
        for (std::size_t t = 0; t < m.mesh.triangles.size(); ++t) {
            if (!StartsWith(m.part_names[m.triangle_parts[t]], "seat")) continue;
            for (int k = 0; k < 3; ++k) {
                seat_top = std::max(seat_top, m.mesh.vertices[m.mesh.triangles[t][k]].z());
            }
        }
        // The back: the chair_back parts, else whatever rises above the seat.
        if (!AreaCentroid(m, {"chair_back"}, a) &&
            !AreaCentroid(
                m, {}, [&](const Eigen::Vector3f& c) { return c.z() > seat_top + 0.1f; }, a)) {
            return 0.0f;
        }
        Eigen::Vector3f d = seat - a;
        d.z() = 0.0f;
        return d.norm() > 1e-3f ? SnappedYaw(d) : 0.0f;
    }
    if (category == "table") {
        // Long side along y; the drawers' side (if any) in front.
        const Eigen::Vector3f size = box.sizes();
        float yaw = size.x() > size.y() ? kPi / 2 : 0.0f;
        if (AreaCentroid(m, {"drawer", "handle"}, b)) {
            const Eigen::Vector3f d =
                Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()) * (b - centre);
            if (d.x() < 0.0f) yaw += kPi;
        }
        return yaw;
    }
    // Cabinets and sideboards: away from the back panel, else towards the doors and drawers.
    Eigen::Vector3f d = Eigen::Vector3f::Zero();
    if (AreaCentroid(m, {"back_panel"}, a)) {
        d = centre - a;
    } else if (AreaCentroid(m, {"door", "drawer", "handle"}, b)) {
        d = b - centre;
    }
    d.z() = 0.0f;
    return d.norm() > 1e-3f ? SnappedYaw(d) : 0.0f;
}

// The closed kitchen model as one mesh (links placed by the closed joint state).
PartMesh MergeClosed(const ArticulatedModel& model) {
    PartMesh out;
    const auto poses = model.LinkPoses(model.ClosedState());
    for (std::size_t l = 0; l < model.links.size(); ++l) {
        if (!model.links[l].mesh) continue;
        PartMesh link = *model.links[l].mesh;
        for (auto& v : link.mesh.vertices) v = poses[l] * v;
        for (auto& n : link.mesh.vertex_normals) n = poses[l].linear() * n;
        out.AppendParts(link);
    }
    return out;
}

using math_internal::U;
bool Chance(StreamRng& rng, float p) { return rng.Uniform() < p; }

using V3 = Eigen::Vector3f;

Eigen::Matrix3f RotY(float a) { return Eigen::AngleAxisf(a, V3::UnitY()).toRotationMatrix(); }
Eigen::Matrix3f RotZ(float a) { return Eigen::AngleAxisf(a, V3::UnitZ()).toRotationMatrix(); }

// Four legs of side `s` (square section) from z0 to z1, inset `inset` from a w x d rectangle.
void FourLegs(PartMesh& m, float w, float d, float s, float inset, float z0, float z1) {
    for (int i = 0; i < 4; ++i) {
        const float x = (i & 1 ? 1.0f : -1.0f) * (d / 2 - inset - s / 2);
        const float y = (i & 2 ? 1.0f : -1.0f) * (w / 2 - inset - s / 2);
        AddBoard(m, V3(s, s, z1 - z0), V3(x, y, (z0 + z1) / 2), "leg");
    }
}

// Chairs: front +x, the back behind the seat at -x.
PartMesh Chair(StreamRng& rng) {
    PartMesh m;
    const float w = U(rng, 0.40f, 0.52f), d = U(rng, 0.40f, 0.50f);
    const bool pedestal = Chance(rng, 0.35f);
    const float seat_t = pedestal ? U(rng, 0.05f, 0.10f) : U(rng, 0.02f, 0.05f);
    const float h = U(rng, 0.42f, 0.48f);  // seat top
    AddBoard(m, V3(d, w, seat_t), V3(0, 0, h - seat_t / 2), "seat");
    if (pedestal) {
        const float base_z = U(rng, 0.06f, 0.10f);
        AddBoard(m, V3(0.05f, 0.05f, h - seat_t - base_z), V3(0, 0, (h - seat_t + base_z) / 2),
                 "central_support");
        const float arm = U(rng, 0.28f, 0.34f);
        const float a0 = U(rng, 0.0f, 2 * kPi);
        for (int k = 0; k < 5; ++k) {
            const Eigen::Matrix3f R = RotZ(a0 + 2 * kPi * static_cast<float>(k) / 5);
            AddBoard(m, V3(arm, 0.04f, 0.03f), R * V3(arm / 2, 0, base_z - 0.015f), "leg", R);
            AddBoard(m, V3(0.05f, 0.03f, base_z - 0.03f),
                     R * V3(arm - 0.02f, 0, (base_z - 0.03f) / 2), "caster", R);
        }
    } else {
        const float s = U(rng, 0.025f, 0.045f);
        FourLegs(m, w, d, s, U(rng, 0.0f, 0.02f), 0.0f, h - seat_t);
        if (Chance(rng, 0.5f)) {  // stretchers
            const float z = U(rng, 0.10f, 0.22f);
            AddBoard(m, V3(d - 0.04f, 0.02f, 0.02f), V3(0, w / 2 - 0.03f, z), "bar_stretcher");
            AddBoard(m, V3(d - 0.04f, 0.02f, 0.02f), V3(0, -w / 2 + 0.03f, z), "bar_stretcher");
        }
    }
    // Back: a board or slats between two posts, tilted backwards.
    const float back_h = U(rng, 0.28f, 0.50f), back_t = U(rng, 0.02f, 0.05f);
    const float tilt = U(rng, 0.0f, 0.25f);
    const Eigen::Matrix3f R = RotY(-tilt);
    const V3 base(-d / 2 + back_t / 2, 0, h);
    const float bw = pedestal ? U(rng, 0.36f, w) : w;
    if (pedestal || Chance(rng, 0.6f)) {
        const float gap = pedestal ? U(rng, 0.04f, 0.12f) : U(rng, 0.0f, 0.15f);
        const float board = back_h - gap;
        AddBoard(m, V3(back_t, bw, board), base + R * V3(0, 0, gap + board / 2), "chair_back", R);
        if (gap > 0.0f) {
            AddBoard(m, V3(back_t, 0.05f, gap), base + R * V3(0, 0, gap / 2), "chair_back", R);
        }
    } else {
        const int slats = rng.UniformInt(2, 4);
        for (int side = -1; side <= 1; side += 2) {
            AddBoard(m, V3(back_t, 0.035f, back_h),
                     base + R * V3(0, side * (bw / 2 - 0.0175f), back_h / 2), "chair_back", R);
        }
        AddBoard(m, V3(back_t, bw, 0.07f), base + R * V3(0, 0, back_h - 0.035f), "chair_back", R);
        for (int k = 0; k < slats; ++k) {
            const float y =
                -bw / 2 + bw * static_cast<float>(k + 1) / static_cast<float>(slats + 1);
            AddBoard(m, V3(back_t * 0.8f, 0.03f, back_h - 0.1f),
                     base + R * V3(0, y, (back_h - 0.1f) / 2), "chair_back", R);
        }
    }
    if (Chance(rng, 0.3f)) {  // arms
        const float z = h + U(rng, 0.18f, 0.25f);
        for (int side = -1; side <= 1; side += 2) {
            const float y = side * (w / 2 + 0.02f);
            AddBoard(m, V3(d * 0.8f, 0.05f, 0.03f), V3(-d * 0.05f, y, z), "chair_arm");
            AddBoard(m, V3(0.03f, 0.03f, z - h), V3(d * 0.25f, y, (z + h) / 2), "chair_arm");
        }
    }
    return m;
}

// Tables: long side along y.
PartMesh Table(StreamRng& rng) {
    PartMesh m;
    const float t = U(rng, 0.025f, 0.05f), h = U(rng, 0.70f, 0.78f);
    const float style = static_cast<float>(rng.Uniform());
    if (style < 0.2f) {  // round, on a column and a cross base
        const float r = U(rng, 0.35f, 0.60f);
        PartMesh top = MakeRevolutionMesh(
            {{0.0f, h - t, 0}, {r, h - t, 0}, {r, h, 0}, {0.0f, h, 0}}, {"tabletop"}, 32);
        m.AppendParts(top);
        AddBoard(m, V3(0.08f, 0.08f, h - t - 0.04f), V3(0, 0, (h - t + 0.04f) / 2), "leg");
        const float foot = U(rng, 0.25f, 0.40f);
        for (int k = 0; k < 2; ++k) {
            AddBoard(m, V3(2 * foot, 0.06f, 0.04f), V3(0, 0, 0.02f), "leg", RotZ(kPi / 2 * k));
        }
        return m;
    }
    const float d = U(rng, 0.60f, 1.00f), w = std::max(d, U(rng, 0.80f, 2.00f));
    AddBoard(m, V3(d, w, t), V3(0, 0, h - t / 2), "tabletop");
    if (style < 0.75f) {  // four legs, perhaps an apron
        const float s = U(rng, 0.04f, 0.08f), inset = U(rng, 0.02f, 0.10f);
        FourLegs(m, w, d, s, inset, 0.0f, h - t);
        if (Chance(rng, 0.6f)) {
            const float ah = U(rng, 0.06f, 0.12f), at = 0.02f;
            const float x = d / 2 - inset - s / 2, y = w / 2 - inset - s / 2;
            AddBoard(m, V3(at, 2 * y, ah), V3(x, 0, h - t - ah / 2), "bar_stretcher");
            AddBoard(m, V3(at, 2 * y, ah), V3(-x, 0, h - t - ah / 2), "bar_stretcher");
            AddBoard(m, V3(2 * x, at, ah), V3(0, y, h - t - ah / 2), "bar_stretcher");
            AddBoard(m, V3(2 * x, at, ah), V3(0, -y, h - t - ah / 2), "bar_stretcher");
        }
    } else {  // desk on two side panels, a modesty panel at the back, perhaps a drawer unit
        const float pt = U(rng, 0.025f, 0.04f), inset = U(rng, 0.0f, 0.05f);
        for (int side = -1; side <= 1; side += 2) {
            AddBoard(m, V3(d - 2 * inset, pt, h - t),
                     V3(0, side * (w / 2 - inset - pt / 2), (h - t) / 2), "vertical_side_panel");
        }
        if (Chance(rng, 0.7f)) {
            const float ph = U(rng, 0.25f, 0.45f);
            AddBoard(m, V3(0.02f, w - 2 * inset - 2 * pt, ph),
                     V3(-d / 2 + inset + 0.05f, 0, h - t - ph / 2), "back_panel");
        }
        if (Chance(rng, 0.5f)) {
            const float uw = U(rng, 0.35f, 0.45f), uh = U(rng, 0.45f, h - t - 0.05f);
            const float y = w / 2 - inset - pt - uw / 2;
            AddBoard(m, V3(d - 2 * inset - 0.05f, uw, uh), V3(0, y, h - t - uh / 2), "drawer");
        }
    }
    return m;
}

// Cabinets and sideboards: a body of boards with its front at +x, on a plinth or legs, with
// doors, drawers or open shelves.
PartMesh Storage(StreamRng& rng, bool sideboard) {
    PartMesh m;
    const float d = sideboard ? U(rng, 0.38f, 0.60f) : U(rng, 0.35f, 0.62f);
    const float w = sideboard ? U(rng, 1.20f, 2.20f) : U(rng, 0.40f, 1.00f);
    const float h = sideboard ? U(rng, 0.50f, 0.90f)
                              : (Chance(rng, 0.2f) ? U(rng, 1.40f, 2.00f) : U(rng, 0.70f, 1.00f));
    const bool legs = Chance(rng, sideboard ? 0.5f : 0.25f);
    const float base = legs ? U(rng, 0.10f, 0.25f) : U(rng, 0.0f, 0.10f);
    const float bt = U(rng, 0.016f, 0.03f);
    if (legs) {
        FourLegs(m, w, d, U(rng, 0.03f, 0.05f), 0.02f, 0.0f, base);
    } else if (base > 0.0f) {
        AddBoard(m, V3(d - 0.06f, w - 0.04f, base), V3(-0.03f, 0, base / 2), "base_side_panel");
    }
    const float z0 = base, z1 = h;
    const float overhang = Chance(rng, 0.5f) ? U(rng, 0.0f, 0.04f) : 0.0f;
    AddBoard(m, V3(d + overhang, w + 2 * overhang, bt), V3(overhang / 2, 0, z1 - bt / 2),
             sideboard ? "tabletop" : "top_panel");
    AddBoard(m, V3(d, w, bt), V3(0, 0, z0 + bt / 2), "bottom_panel");
    for (int side = -1; side <= 1; side += 2) {
        AddBoard(m, V3(d, bt, z1 - z0 - 2 * bt), V3(0, side * (w / 2 - bt / 2), (z0 + z1) / 2),
                 "vertical_side_panel");
    }
    AddBoard(m, V3(bt, w - 2 * bt, z1 - z0 - 2 * bt), V3(-d / 2 + bt / 2, 0, (z0 + z1) / 2),
             "back_panel");
    const float inner_h = z1 - z0 - 2 * bt, inner_w = w - 2 * bt;
    const float style = static_cast<float>(rng.Uniform());
    const int columns = std::max(1, static_cast<int>(std::round(inner_w / U(rng, 0.35f, 0.6f))));
    const float cw = inner_w / static_cast<float>(columns);
    if (style < 0.2f) {  // open shelves
        const int shelves = std::max(1, static_cast<int>(inner_h / U(rng, 0.25f, 0.40f)) - 1);
        for (int k = 1; k <= shelves; ++k) {
            const float z =
                z0 + bt + inner_h * static_cast<float>(k) / static_cast<float>(shelves + 1);
            AddBoard(m, V3(d - 2 * bt, inner_w, bt), V3(0, 0, z), "shelf");
        }
        for (int c = 1; c < columns; ++c) {
            AddBoard(m, V3(d - 2 * bt, bt, inner_h), V3(0, -inner_w / 2 + cw * c, (z0 + z1) / 2),
                     "vertical_divider_panel");
        }
        return m;
    }
    const float gap = 0.004f, ft = 0.018f, x = d / 2 + ft / 2;
    const bool drawers = style > 0.65f;
    for (int c = 0; c < columns; ++c) {
        const float yc = -inner_w / 2 + cw * (static_cast<float>(c) + 0.5f);
        const int rows = drawers ? rng.UniformInt(2, 4) : 1;
        for (int r = 0; r < rows; ++r) {
            const float rh = inner_h / static_cast<float>(rows);
            const float zc = z0 + bt + rh * (static_cast<float>(r) + 0.5f);
            AddBoard(m, V3(ft, cw - gap, rh - gap), V3(x, yc, zc), drawers ? "drawer" : "door");
            const float hy = drawers ? 0.0f : (c % 2 == 0 ? cw / 2 - 0.05f : -cw / 2 + 0.05f);
            const V3 hsize = drawers ? V3(0.025f, 0.12f, 0.02f) : V3(0.025f, 0.02f, 0.12f);
            const float hz = drawers ? zc : std::min(zc + rh * 0.3f, z1 - 0.1f);
            AddBoard(m, hsize, V3(x + ft / 2 + 0.0125f, yc + hy, hz), "handle");
        }
    }
    return m;
}

}  // namespace

void AddBoard(PartMesh& mesh, const Eigen::Vector3f& extents, const Eigen::Vector3f& center,
              const std::string& part, const Eigen::Matrix3f& R) {
    PartMesh b = MakeBoxMesh(extents, part);
    for (auto& v : b.mesh.vertices) v = center + R * (v - V3(0, 0, extents.z() / 2));
    for (auto& n : b.mesh.vertex_normals) n = R * n;
    mesh.AppendParts(b);
}

std::vector<FurnitureEntry> ReadFurnitureLibrary(const std::filesystem::path& furniture,
                                                 const std::filesystem::path& kitchen) {
    if (furniture.empty() && kitchen.empty()) {
        throw InvalidArgument(
            "furniture library: give a furniture folder, a kitchen folder or both");
    }
    std::vector<FurnitureEntry> out;
    std::map<std::string, bool> seen;
    if (!furniture.empty()) {
        for (const auto& e : ReadMeshLibrary(furniture, FurnitureCategories())) {
            FurnitureEntry f;
            f.path = e.file;
            f.category = e.category;
            f.id = e.file.stem().string();
            f.model_id = AfterLast(f.id, '_');
            f.source = "furniture";
            f.scale_to_m = e.scale_to_m;
            seen[f.model_id] = true;
            out.push_back(std::move(f));
        }
    }
    if (!kitchen.empty()) {
        for (const auto& e : ReadKitchenLibrary(kitchen)) {
            const std::string category = KitchenFurnitureCategory(e.kind);
            if (category.empty()) continue;
            FurnitureEntry f;
            f.path = e.folder;
            f.category = category;
            f.id = e.id;
            f.model_id = AfterLast(e.id, '/');
            f.source = "kitchen";
            f.scale_to_m = e.scale_to_m;
            if (seen.count(f.model_id)) continue;  // the same model as a furniture file
            seen[f.model_id] = true;
            out.push_back(std::move(f));
        }
    }
    return out;
}

std::vector<MeshSplit> FurnitureSplitOf(const std::vector<FurnitureEntry>& library) {
    std::vector<MeshSplit> split(library.size(), MeshSplit::kTune);
    std::map<std::string, std::vector<std::size_t>> by_category;
    for (std::size_t i = 0; i < library.size(); ++i) by_category[library[i].category].push_back(i);
    for (auto& [category, idx] : by_category) {
        std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
            const auto ha = MeshNameHash(library[a].model_id),
                       hb = MeshNameHash(library[b].model_id);
            return ha != hb ? ha < hb : library[a].model_id < library[b].model_id;
        });
        for (std::size_t k = 0; k < idx.size(); ++k) {
            split[idx[k]] = k % 2 == 0 ? MeshSplit::kTune : MeshSplit::kTest;
        }
    }
    return split;
}

std::vector<FurnitureEntry> SelectFurnitureSplit(const std::vector<FurnitureEntry>& library,
                                                 MeshSplit split) {
    if (split == MeshSplit::kAll) return library;
    const auto halves = FurnitureSplitOf(library);
    std::vector<FurnitureEntry> out;
    for (std::size_t i = 0; i < library.size(); ++i) {
        if (halves[i] == split) out.push_back(library[i]);
    }
    return out;
}

FurniturePiece LoadFurniturePiece(const FurnitureEntry& entry) {
    FurniturePiece piece;
    piece.category = entry.category;
    piece.id = entry.id;
    piece.source = entry.source;
    piece.scale = entry.scale_to_m;
    PartMesh m;
    if (entry.source == "kitchen") {
        const ArticulatedModel model =
            LoadArticulatedModel(entry.path, {.scale = entry.scale_to_m});
        m = MergeClosed(model);
        Canonicalise(m, 0.0f);
    } else {
        m = LoadMesh(entry.path, {.scale = entry.scale_to_m});
        Canonicalise(m, FrontYaw(m, entry.category));
    }
    if (m.mesh.triangles.empty()) {
        throw DataError(fmt::format("{}: furniture model without triangles", entry.path.string()));
    }
    m.name = entry.id;
    piece.mesh = std::make_shared<const PartMesh>(std::move(m));
    return piece;
}

float FurnitureWidth(const PartMesh& mesh) {
    const Eigen::Vector3f size = mesh.Bounds().sizes();
    return std::min(size.x(), size.y());
}

FurniturePiece MakeProceduralFurniture(const std::string& category, StreamRng& rng) {
    PartMesh m;
    if (category == "chair") {
        m = Chair(rng);
    } else if (category == "table") {
        m = Table(rng);
    } else if (category == "cabinet") {
        m = Storage(rng, false);
    } else if (category == "sideboard") {
        m = Storage(rng, true);
    } else {
        throw InvalidArgument(fmt::format(
            "procedural furniture: category must be table, chair, cabinet or sideboard, got '{}'",
            category));
    }
    Canonicalise(m, 0.0f);
    FurniturePiece piece;
    piece.category = category;
    piece.source = "procedural";
    piece.id = fmt::format("procedural/{}", category);
    m.name = piece.id;
    piece.mesh = std::make_shared<const PartMesh>(std::move(m));
    return piece;
}

}  // namespace multicue::sim
