// Procedural kitchen units (MakeProceduralUnit): a carcass of boards, a layout of fronts, handles.
//
// Everything is built in the unit's frame: x in [-depth, 0] for the carcass with the fronts in
// [0, thickness] in front of it, y across the width centred on 0, z up from the floor. The model
// frame of LoadArticulatedModel (bounding box centred, bottom at 0) is that frame shifted.
#include "multicue/sim/kitchen_procedural.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/rng.hpp"

namespace multicue::sim {
namespace {

constexpr float kBoard = 0.018f;  // carcass board thickness [m]

struct Paint {
    Color color;
    float reflectance = 0.5f;
};

std::uint8_t Channel(double v) { return static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0)); }

/// The colour with the laser reflectance LoadArticulatedModel gives a material of it.
Paint MakePaint(double r, double g, double b, float specular_factor = 1.0f) {
    const Color c{Channel(r), Channel(g), Channel(b), 255};
    const float lum = (0.299f * c.r + 0.587f * c.g + 0.114f * c.b) / 255.0f;
    return Paint{c, (0.1f + 0.8f * lum) * specular_factor};
}

/// A front or carcass colour: white, greys, anthracite, woods and a few painted colours, jittered.
Paint RandomFinish(StreamRng& rng) {
    static const float palette[][3] = {{244, 243, 238}, {232, 230, 222}, {205, 205, 200},
                                       {150, 150, 146}, {62, 62, 66},    {196, 158, 112},
                                       {152, 108, 70},  {96, 66, 44},    {140, 160, 132},
                                       {52, 66, 96},    {150, 46, 42},   {220, 205, 170}};
    const auto& c = palette[rng.UniformInt(0, 11)];
    const double j = rng.Uniform(-10, 10);
    return MakePaint(c[0] + j, c[1] + j, c[2] + j);
}

/// Appends `piece` to `m` turned so that its +z axis runs along `up` (unit) and moved to `at`, in
/// the colour and reflectance of `paint`.
void AppendPlaced(PartMesh& m, PartMesh piece, const Eigen::Vector3f& up, const Eigen::Vector3f& at,
                  const Paint& paint) {
    const Eigen::Quaternionf q = Eigen::Quaternionf::FromTwoVectors(Eigen::Vector3f::UnitZ(), up);
    for (auto& v : piece.mesh.vertices) v = q * v + at;
    for (auto& n : piece.mesh.vertex_normals) n = q * n;
    piece.mesh.vertex_colors.assign(piece.mesh.vertices.size(), paint.color);
    piece.vertex_reflectance.assign(piece.mesh.vertices.size(), paint.reflectance);
    m.AppendParts(piece);
}

/// Appends a box spanning [lo, hi] (unit frame) to `m` as part `part`.
void AddBlock(PartMesh& m, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
              const std::string& part, const Paint& paint) {
    AppendPlaced(m, MakeBoxMesh(hi - lo, part), Eigen::Vector3f::UnitZ(),
                 {(lo.x() + hi.x()) / 2, (lo.y() + hi.y()) / 2, lo.z()}, paint);
}

/// Appends a cylinder (or, with few segments, a prism) of `radius` about the line through `from`
/// and `to`.
void AddRod(PartMesh& m, const Eigen::Vector3f& from, const Eigen::Vector3f& to, float radius,
            const std::string& part, const Paint& paint, int segments) {
    const float len = (to - from).norm();
    AppendPlaced(
        m,
        MakeRevolutionMesh({{0.0f, 0.0f, 0}, {radius, 0.0f, 0}, {radius, len, 0}, {0.0f, len, 0}},
                           {part}, segments),
        (to - from) / len, from, paint);
}

/// A knob standing out of the surface x = x0 at (y, z) along +x.
void AddKnob(PartMesh& m, float x0, float y, float z, float reach, float radius,
             const Paint& paint) {
    const float stem = std::max(0.004f, 0.45f * radius);
    const std::vector<ProfilePoint> profile = {{0.0f, 0.0f, 0},          {stem * 1.4f, 0.0f, 0},
                                               {stem, 0.35f * reach, 0}, {radius, 0.6f * reach, 0},
                                               {radius, reach, 0},       {0.0f, reach, 0}};
    AppendPlaced(m, MakeRevolutionMesh(profile, {"knob"}, 24), Eigen::Vector3f::UnitX(), {x0, y, z},
                 paint);
}

/// One handle design, shared by a unit's fronts.
struct HandleDesign {
    enum class Kind { kBar, kKnob } kind = Kind::kBar;
    float length = 0.2f;      ///< bar length [m]
    float diameter = 0.012f;  ///< bar or knob stem thickness [m]
    float reach = 0.03f;      ///< out of the front's surface to the bar's far side [m]
    int segments = 12;        ///< 4: a square bar
    float knob_radius = 0.015f;
    bool sideways = false;  ///< door handles horizontal instead of vertical
    Paint paint;
};

HandleDesign RandomHandle(StreamRng& rng) {
    HandleDesign h;
    const double u = rng.Uniform();
    h.kind = u < 0.85 ? HandleDesign::Kind::kBar : HandleDesign::Kind::kKnob;
    // Lengths skewed towards the common 10-20 cm, up to long bars.
    const double l = rng.Uniform();
    h.length = static_cast<float>(0.06 + 0.54 * l * l);
    h.diameter = static_cast<float>(rng.Uniform(0.007, 0.016));
    h.reach = static_cast<float>(rng.Uniform(0.015, 0.045));
    h.segments = rng.Uniform() < 0.3 ? 4 : 12;
    h.knob_radius = static_cast<float>(rng.Uniform(0.009, 0.02));
    h.sideways = rng.Uniform() < 0.15;
    const double c = rng.Uniform();
    if (c < 0.65) {
        const double g = rng.Uniform(150, 205);
        h.paint = MakePaint(g, g, g + 4, 0.75f);  // brushed metal
    } else {
        const double g = rng.Uniform(25, 60);
        h.paint = MakePaint(g, g, g);
    }
    return h;
}

/// A front's rectangle on the carcass's face (y0 < y1, z0 < z1) and how it moves.
struct FrontRect {
    /// kFlap: hinged at its top edge (wall cupboards); kFlapLow: at its bottom edge (ovens,
    /// dishwashers)
    enum class Type { kDrawer, kDoorHingeLow, kDoorHingeHigh, kFlap, kFlapLow, kPanel } type;
    float y0, y1, z0, z1;
};

/// Where on a front its handle goes: centre (y, z), and whether the handle runs along y.
struct HandlePlace {
    float y = 0, z = 0;
    bool horizontal = true;
    float max_length = 0;
};

HandlePlace PlaceHandle(const FrontRect& f, const HandleDesign& h, bool wall_unit, float unit_top,
                        StreamRng& rng) {
    HandlePlace p;
    const float w = f.y1 - f.y0, ht = f.z1 - f.z0;
    const float inset = static_cast<float>(rng.Uniform(0.035, 0.065));
    switch (f.type) {
        case FrontRect::Type::kDrawer:
        case FrontRect::Type::kPanel:
            p.horizontal = true;
            p.y = (f.y0 + f.y1) / 2;
            p.z = ht < 0.24f ? (f.z0 + f.z1) / 2 : f.z1 - inset;
            p.max_length = w - 0.08f;
            break;
        case FrontRect::Type::kFlap:
            p.horizontal = true;
            p.y = (f.y0 + f.y1) / 2;
            p.z = f.z0 + inset;
            p.max_length = w - 0.08f;
            break;
        case FrontRect::Type::kFlapLow:
            p.horizontal = true;
            p.y = (f.y0 + f.y1) / 2;
            p.z = f.z1 - inset;
            p.max_length = w - 0.08f;
            break;
        case FrontRect::Type::kDoorHingeLow:
        case FrontRect::Type::kDoorHingeHigh: {
            const bool free_high = f.type == FrontRect::Type::kDoorHingeLow;
            // Handles near the edge a hand reaches: the top of low doors, the bottom of wall
            // doors, the middle of tall ones.
            const bool tall_door = ht > 1.0f;
            float zc = wall_unit ? f.z0 + inset : f.z1 - inset;
            if (tall_door) zc = std::clamp(1.05f, f.z0 + 0.2f, f.z1 - 0.2f);
            if (!wall_unit && !tall_door && f.z0 > 0.9f && unit_top > 1.5f) zc = f.z0 + inset;
            if (h.sideways) {
                p.horizontal = true;
                p.max_length = w - 0.08f;
                p.y = free_high ? f.y1 - inset - 0.5f * std::min(h.length, p.max_length)
                                : f.y0 + inset + 0.5f * std::min(h.length, p.max_length);
                p.z = zc;
            } else {
                p.horizontal = false;
                p.max_length = ht - 0.08f;
                const float half = 0.5f * std::min(h.length, p.max_length);
                p.y = free_high ? f.y1 - inset : f.y0 + inset;
                p.z = wall_unit && !tall_door ? zc + half : tall_door ? zc : zc - half;
                p.z = std::clamp(p.z, f.z0 + 0.04f + half, f.z1 - 0.04f - half);
            }
            break;
        }
    }
    return p;
}

/// Appends front `f` (unit frame, on the surface x = 0) with its handle to `m`.
void BuildFront(PartMesh& m, const FrontRect& f, float thickness, bool framed, const Paint& paint,
                const HandleDesign& h, bool wall_unit, float unit_top, StreamRng& rng) {
    const float w = f.y1 - f.y0, ht = f.z1 - f.z0;
    const float frame = static_cast<float>(rng.Uniform(0.045, 0.075));
    if (framed && w > 3.2f * frame && ht > 3.2f * frame) {
        const float recess = 0.006f;
        const float xb = thickness - recess;
        AddBlock(m, {0, f.y0, f.z0}, {xb, f.y1, f.z1}, "door_surface", paint);
        AddBlock(m, {xb, f.y0, f.z0}, {thickness, f.y1, f.z0 + frame}, "door_frame", paint);
        AddBlock(m, {xb, f.y0, f.z1 - frame}, {thickness, f.y1, f.z1}, "door_frame", paint);
        AddBlock(m, {xb, f.y0, f.z0 + frame}, {thickness, f.y0 + frame, f.z1 - frame}, "door_frame",
                 paint);
        AddBlock(m, {xb, f.y1 - frame, f.z0 + frame}, {thickness, f.y1, f.z1 - frame}, "door_frame",
                 paint);
    } else {
        AddBlock(m, {0, f.y0, f.z0}, {thickness, f.y1, f.z1}, "door_surface", paint);
    }
    if (f.type == FrontRect::Type::kPanel) return;
    const HandlePlace p = PlaceHandle(f, h, wall_unit, unit_top, rng);
    const float x0 = thickness;
    if (h.kind == HandleDesign::Kind::kKnob || p.max_length < 0.06f) {
        AddKnob(m, x0, p.y, p.z, h.reach, h.knob_radius, h.paint);
        return;
    }
    const float len = std::min(h.length, p.max_length);
    const float r = h.diameter / 2;
    const float xc = x0 + h.reach - r;
    const Eigen::Vector3f dir = p.horizontal ? Eigen::Vector3f::UnitY() : Eigen::Vector3f::UnitZ();
    const Eigen::Vector3f c(xc, p.y, p.z);
    AddRod(m, c - dir * (len / 2), c + dir * (len / 2), r, "handle", h.paint, h.segments);
    const float mount_in = std::min(0.5f * len - r, std::max(r, 0.08f * len));
    for (const float s : {-1.0f, 1.0f}) {
        const Eigen::Vector3f at = c + dir * (s * (len / 2 - mount_in));
        AddRod(m, Eigen::Vector3f(x0, at.y(), at.z()), Eigen::Vector3f(xc, at.y(), at.z()),
               0.8f * r, "handle", h.paint, h.segments);
    }
}

/// The layout of a unit's fronts on its face [y0, y1] x [z0, z1], `gap` between fronts.
struct Layout {
    float width = 0.6f, depth = 0.58f, height = 0.85f, plinth = 0.1f;
    std::vector<FrontRect> fronts;
};

/// Splits the row [z0, z1] into one or two fronts of `type` (doors: hinged on the outer edges).
void AddRow(Layout& L, float y0, float y1, float z0, float z1, float gap, int columns,
            FrontRect::Type type, StreamRng& rng) {
    if (columns <= 1) {
        FrontRect::Type t = type;
        if (type == FrontRect::Type::kDoorHingeLow && rng.Uniform() < 0.5) {
            t = FrontRect::Type::kDoorHingeHigh;
        }
        L.fronts.push_back({t, y0, y1, z0, z1});
        return;
    }
    const float mid = (y0 + y1) / 2;
    const bool doors = type == FrontRect::Type::kDoorHingeLow;
    L.fronts.push_back({doors ? FrontRect::Type::kDoorHingeLow : type, y0, mid - gap / 2, z0, z1});
    L.fronts.push_back({doors ? FrontRect::Type::kDoorHingeHigh : type, mid + gap / 2, y1, z0, z1});
}

bool IsAppliance(const std::string& kind) {
    const auto& a = ProceduralApplianceKinds();
    return std::find(a.begin(), a.end(), kind) != a.end();
}

/// Appliances: a dishwasher (a flap hinged at its bottom under a control strip), an oven (a flap
/// under a panel of knobs, now and then over a storage drawer) and a fridge (tall, with or
/// without a freezer door under it, or under the counter), in the sizes of built-in appliances.
Layout RandomApplianceLayout(const std::string& kind, StreamRng& rng, float gap) {
    Layout L;
    auto U = [&rng](double a, double b) { return static_cast<float>(rng.Uniform(a, b)); };
    using T = FrontRect::Type;
    const bool tall_fridge = kind == "fridge" && rng.Uniform() < 0.6;
    if (kind == "fridge") {
        L.width = tall_fridge ? U(0.55, 0.72) : U(0.48, 0.6);
        L.depth = tall_fridge ? U(0.6, 0.7) : U(0.55, 0.6);
        L.height = tall_fridge ? U(1.6, 2.0) : U(0.8, 0.88);
        L.plinth = U(0.0, 0.03);
    } else {
        L.width = kind == "dishwasher" && rng.Uniform() < 0.25 ? U(0.44, 0.46) : U(0.57, 0.6);
        L.depth = U(0.55, 0.6);
        L.height = U(0.8, 0.88);
        L.plinth = U(0.08, 0.12);
    }
    const float y0 = -L.width / 2 + gap / 2, y1 = L.width / 2 - gap / 2;
    const float z0 = L.plinth + gap / 2, z1 = L.height - gap / 2;
    if (kind == "fridge") {
        // Both doors hinged on one side.
        const T side = rng.Uniform() < 0.5 ? T::kDoorHingeLow : T::kDoorHingeHigh;
        if (tall_fridge && rng.Uniform() < 0.6) {
            const float split = z0 + U(0.55, 0.9);
            L.fronts.push_back({side, y0, y1, z0, split - gap / 2});
            L.fronts.push_back({side, y0, y1, split + gap / 2, z1});
        } else {
            L.fronts.push_back({side, y0, y1, z0, z1});
        }
    } else if (kind == "dishwasher") {
        const float strip = rng.Uniform() < 0.5 ? U(0.06, 0.11) : 0.0f;
        if (strip > 0.0f) L.fronts.push_back({T::kPanel, y0, y1, z1 - strip, z1});
        L.fronts.push_back({T::kFlapLow, y0, y1, z0, z1 - (strip > 0.0f ? strip + gap : 0.0f)});
    } else {  // oven
        const float panel = U(0.08, 0.13);
        const float drawer = rng.Uniform() < 0.6 ? U(0.12, 0.2) : 0.0f;
        L.fronts.push_back({T::kPanel, y0, y1, z1 - panel, z1});
        L.fronts.push_back(
            {T::kFlapLow, y0, y1, z0 + (drawer > 0.0f ? drawer + gap : 0.0f), z1 - panel - gap});
        if (drawer > 0.0f) L.fronts.push_back({T::kDrawer, y0, y1, z0, z0 + drawer});
    }
    return L;
}

Layout RandomLayout(const std::string& kind, StreamRng& rng, float gap) {
    if (IsAppliance(kind)) return RandomApplianceLayout(kind, rng, gap);
    Layout L;
    auto U = [&rng](double a, double b) { return static_cast<float>(rng.Uniform(a, b)); };
    const bool wall = kind == "wall_cupboard";
    const bool tall = kind == "tall_cupboard";
    if (wall) {
        L.width = U(0.3, 1.0);
        L.depth = U(0.3, 0.38);
        L.height = rng.Uniform() < 0.2 ? U(0.32, 0.48) : U(0.5, 0.95);
        L.plinth = 0.0f;
    } else if (tall) {
        L.width = U(0.42, 0.65);
        L.depth = U(0.52, 0.62);
        L.height = U(1.8, 2.2);
        L.plinth = U(0.08, 0.13);
    } else {
        L.width = kind == "sink_cupboard" ? U(0.8, 1.2) : U(0.4, 1.0);
        L.depth = U(0.5, 0.62);
        L.height = U(0.72, 0.9);
        L.plinth = U(0.08, 0.13);
    }
    const float y0 = -L.width / 2 + gap / 2, y1 = L.width / 2 - gap / 2;
    const float z0 = L.plinth + gap / 2, z1 = L.height - gap / 2;
    const int door_columns = L.width < 0.58f ? 1 : L.width > 0.75f ? 2 : rng.UniformInt(1, 2);
    using T = FrontRect::Type;
    if (kind == "drawer_unit") {
        int n = rng.UniformInt(2, 6);
        const double style = rng.Uniform();
        // Pan drawers: two or three, the lowest as tall as a low door.
        const bool pans = style >= 0.8;
        if (pans) n = 2 + n % 2;
        std::vector<float> share(static_cast<std::size_t>(n), 1.0f);
        if (style < 0.35) {
            for (int i = 0; i < n; ++i) share[static_cast<std::size_t>(i)] = 1.0f + 0.35f * i;
        } else if (style < 0.6 && n >= 3) {
            share[0] = 0.5f;
        }
        const float usable = (z1 - z0) - gap * static_cast<float>(n - 1);
        if (pans) {
            // The pan drawer 40-56 cm (leaving at least 12 cm to each drawer above), the
            // drawers above it alike.
            const float pan = std::min(U(0.4, 0.56), usable - 0.12f * static_cast<float>(n - 1));
            for (int i = 0; i + 1 < n; ++i) {
                share[static_cast<std::size_t>(i)] = (usable - pan) / static_cast<float>(n - 1);
            }
            share.back() = pan;
        }
        float total = 0;
        for (const float s : share) total += s;
        float top = z1;
        const bool split_top = L.width > 0.8f && rng.Uniform() < 0.3;
        for (int i = 0; i < n; ++i) {
            const float h = usable * share[static_cast<std::size_t>(i)] / total;
            AddRow(L, y0, y1, top - h, top, gap, i == 0 && split_top ? 2 : 1, T::kDrawer, rng);
            top -= h + gap;
        }
    } else if (kind == "wall_cupboard") {
        if (L.height < 0.5f && rng.Uniform() < 0.7) {
            L.fronts.push_back({T::kFlap, y0, y1, z0, z1});
        } else {
            AddRow(L, y0, y1, z0, z1, gap, door_columns, T::kDoorHingeLow, rng);
        }
    } else if (kind == "tall_cupboard") {
        const double style = rng.Uniform();
        if (style < 0.3) {
            AddRow(L, y0, y1, z0, z1, gap, 1, T::kDoorHingeLow, rng);
        } else if (style < 0.7) {
            const float split = z0 + U(0.75, 1.3);
            AddRow(L, y0, y1, z0, split - gap / 2, gap, 1, T::kDoorHingeLow, rng);
            AddRow(L, y0, y1, split + gap / 2, z1, gap, 1, T::kDoorHingeLow, rng);
        } else {
            const int n = rng.UniformInt(1, 3);
            float top = z0 + U(0.2, 0.3) * static_cast<float>(n);
            AddRow(L, y0, y1, top + gap / 2, z1, gap, 1, T::kDoorHingeLow, rng);
            const float h = (top - z0 - gap * static_cast<float>(n - 1)) / static_cast<float>(n);
            top -= gap / 2;
            for (int i = 0; i < n; ++i) {
                AddRow(L, y0, y1, top - h, top, gap, 1, T::kDrawer, rng);
                top -= h + gap;
            }
        }
    } else {
        // Cupboards and sink cupboards: doors, now and then under a row of drawers (or, on a
        // sink, a fixed panel).
        const double top_row = rng.Uniform();
        const bool sink = kind == "sink_cupboard";
        float doors_top = z1;
        if ((sink && top_row < 0.7) || (!sink && top_row < 0.45)) {
            const float h = U(0.11, 0.2);
            const T type = sink && top_row < 0.4 ? T::kPanel : T::kDrawer;
            const int cols = L.width > 0.75f && rng.Uniform() < 0.5 ? 2 : 1;
            AddRow(L, y0, y1, z1 - h, z1, gap, type == T::kPanel ? 1 : cols, type, rng);
            doors_top = z1 - h - gap;
        }
        AddRow(L, y0, y1, z0, doors_top, gap, door_columns, T::kDoorHingeLow, rng);
    }
    return L;
}

}  // namespace

const std::vector<std::string>& ProceduralUnitKinds() {
    static const std::vector<std::string> kinds = {"cupboard", "sink_cupboard", "drawer_unit",
                                                   "wall_cupboard", "tall_cupboard"};
    return kinds;
}

const std::vector<std::string>& ProceduralApplianceKinds() {
    static const std::vector<std::string> kinds = {"dishwasher", "oven", "fridge"};
    return kinds;
}

ArticulatedModel MakeProceduralUnit(const std::string& kind, std::uint64_t seed) {
    const auto& kinds = ProceduralUnitKinds();
    if (std::find(kinds.begin(), kinds.end(), kind) == kinds.end() && !IsAppliance(kind)) {
        throw InvalidArgument(fmt::format("procedural unit: unknown kind '{}'", kind));
    }
    StreamRng rng(seed, 0x70726f63ull);
    const float gap = static_cast<float>(rng.Uniform(0.002, 0.005));
    const float thickness = static_cast<float>(rng.Uniform(0.016, 0.024));
    Layout L = RandomLayout(kind, rng, gap);
    if (kind == "drawer_unit") {
        // A quarter of the drawer units are as deep as the library's deepest (mini fridge bases,
        // 0.97 m), with boxes to match: pulled out, the front may leave the view while the box's
        // inside is seen behind the face. Drawn from a stream of their own, so that every other
        // draw of the unit stays as it was.
        StreamRng deep(seed, 0x64656570ull);
        if (deep.Uniform() < 0.25) L.depth = static_cast<float>(deep.Uniform(0.8, 1.0));
    }
    Paint front = RandomFinish(rng);
    Paint body = rng.Uniform() < 0.5 ? front : RandomFinish(rng);
    const Paint inside = MakePaint(226, 224, 218);
    bool framed = rng.Uniform() < 0.35;
    HandleDesign handle = RandomHandle(rng);
    const bool wall_unit = kind == "wall_cupboard";
    // Appliances: white, steel or black, flat fronts, bars along the fronts; drawn from a stream
    // of their own, after the draws every unit makes.
    StreamRng extra(seed, 0x6170706cull);
    if (IsAppliance(kind)) {
        const double c = extra.Uniform();
        const double j = extra.Uniform(-6, 6);
        front = c < 0.45   ? MakePaint(240 + j, 240 + j, 236 + j)
                : c < 0.85 ? MakePaint(182 + j, 184 + j, 188 + j, 0.75f)
                           : MakePaint(36 + j, 36 + j, 40 + j);
        body = front;
        framed = false;
        handle.kind = HandleDesign::Kind::kBar;
        handle.sideways = false;
        if (kind == "fridge") handle.length = static_cast<float>(extra.Uniform(0.2, 0.9));
    }

    ArticulatedModel model;
    model.id = fmt::format("procedural/{}/{:016x}", kind, seed);
    model.kind = kind;
    // The carcass: sides, bottom, top, back, a shelf and a recessed plinth.
    PartMesh carcass;
    const float W = L.width, D = L.depth, H = L.height, zb = L.plinth;
    AddBlock(carcass, {-D, -W / 2, zb}, {0, -W / 2 + kBoard, H}, "furniture_body", body);
    AddBlock(carcass, {-D, W / 2 - kBoard, zb}, {0, W / 2, H}, "furniture_body", body);
    AddBlock(carcass, {-D, -W / 2 + kBoard, zb}, {0, W / 2 - kBoard, zb + kBoard}, "furniture_body",
             body);
    AddBlock(carcass, {-D, -W / 2 + kBoard, H - kBoard}, {0, W / 2 - kBoard, H}, "furniture_body",
             body);
    AddBlock(carcass, {-D, -W / 2 + kBoard, zb + kBoard}, {-D + 0.008f, W / 2 - kBoard, H - kBoard},
             "furniture_body", inside);
    AddBlock(carcass, {-D + 0.008f, -W / 2 + kBoard, (zb + H) / 2},
             {-0.03f, W / 2 - kBoard, (zb + H) / 2 + kBoard}, "shelf", inside);
    if (zb > 0.0f) {
        AddBlock(carcass, {-D + 0.05f, -W / 2, 0}, {-0.06f, W / 2, zb}, "furniture_body", body);
    }
    for (const FrontRect& f : L.fronts) {
        if (f.type != FrontRect::Type::kPanel) continue;
        BuildFront(carcass, f, thickness, framed, front, handle, wall_unit, H, rng);
        // An oven's control knobs (two to six), a dishwasher's one or two now and then.
        const int knobs = kind == "oven"         ? extra.UniformInt(2, 6)
                          : kind == "dishwasher" ? extra.UniformInt(0, 2)
                                                 : 0;
        if (knobs == 0) continue;
        const Paint knob = extra.Uniform() < 0.5 ? handle.paint : MakePaint(30, 30, 32);
        const float radius = static_cast<float>(extra.Uniform(0.012, 0.02));
        const float reach = static_cast<float>(extra.Uniform(0.015, 0.028));
        for (int i = 0; i < knobs; ++i) {
            const float y =
                f.y0 + (f.y1 - f.y0) * (static_cast<float>(i) + 0.5f) / static_cast<float>(knobs);
            AddKnob(carcass, thickness, y, (f.z0 + f.z1) / 2, reach, radius, knob);
        }
    }
    carcass.name = model.id + "/base";
    ArticulatedLink base;
    base.name = "base";
    base.joint_kind = "heavy";
    base.semantic = "furniture_body";
    base.mesh = std::make_shared<const PartMesh>(std::move(carcass));
    model.links.push_back(std::move(base));

    for (const FrontRect& f : L.fronts) {
        if (f.type == FrontRect::Type::kPanel) continue;
        PartMesh m;
        BuildFront(m, f, thickness, framed, front, handle, wall_unit, H, rng);
        if (kind == "oven" && f.type == FrontRect::Type::kFlapLow) {
            // The door's window of dark glass, below the handle.
            const float side = static_cast<float>(extra.Uniform(0.06, 0.1));
            AddBlock(m, {thickness, f.y0 + side, f.z0 + side},
                     {thickness + 0.002f, f.y1 - side, f.z1 - std::max(side, 0.1f)}, "door_surface",
                     MakePaint(28, 28, 32, 0.3f));
        }
        ArticulatedJoint j;
        j.parent = 0;
        j.child = static_cast<int>(model.links.size());
        j.name = fmt::format("joint_{}", model.joints.size());
        Eigen::Vector3f origin = Eigen::Vector3f::Zero();
        const float open = static_cast<float>(rng.Uniform(1.57, 2.0));
        ArticulatedLink link;
        link.name = fmt::format("link_{}", model.links.size());
        if (f.type == FrontRect::Type::kDrawer) {
            // The drawer's box behind its front.
            const float bd = 0.8f * D, bh = std::max(0.05f, 0.7f * (f.z1 - f.z0) - 0.02f);
            const float by0 = f.y0 + 0.02f, by1 = f.y1 - 0.02f, bz = f.z0 + 0.02f;
            AddBlock(m, {-bd, by0, bz}, {0, by0 + 0.012f, bz + bh}, "drawer_box", inside);
            AddBlock(m, {-bd, by1 - 0.012f, bz}, {0, by1, bz + bh}, "drawer_box", inside);
            AddBlock(m, {-bd, by0 + 0.012f, bz}, {0, by1 - 0.012f, bz + 0.01f}, "drawer_box",
                     inside);
            AddBlock(m, {-bd, by0 + 0.012f, bz}, {-bd + 0.012f, by1 - 0.012f, bz + bh},
                     "drawer_box", inside);
            j.type = io::UrdfJointType::kPrismatic;
            j.axis = Eigen::Vector3f::UnitX();
            j.lower = 0.0f;
            j.upper = 0.85f * bd;
            link.joint_kind = "slider";
            link.semantic = "drawer";
        } else {
            j.type = io::UrdfJointType::kRevolute;
            j.lower = 0.0f;
            j.upper = open;
            link.joint_kind = "hinge";
            link.semantic = "rotation_door";
            if (f.type == FrontRect::Type::kFlap) {
                origin = Eigen::Vector3f(0, 0, f.z1);
                j.axis = -Eigen::Vector3f::UnitY();
            } else if (f.type == FrontRect::Type::kFlapLow) {
                // Down to the floor side, no farther than level.
                origin = Eigen::Vector3f(0, 0, f.z0);
                j.axis = Eigen::Vector3f::UnitY();
                j.upper = std::min(open, 1.55f);
            } else if (f.type == FrontRect::Type::kDoorHingeLow) {
                origin = Eigen::Vector3f(0, f.y0, 0);
                j.axis = -Eigen::Vector3f::UnitZ();
            } else {
                origin = Eigen::Vector3f(0, f.y1, 0);
                j.axis = Eigen::Vector3f::UnitZ();
            }
        }
        // The link's frame is the joint's: its mesh moves there.
        for (auto& v : m.mesh.vertices) v -= origin;
        j.T_parent_joint = Eigen::Translation3f(origin) * Eigen::Isometry3f::Identity();
        m.name = model.id + "/" + link.name;
        link.mesh = std::make_shared<const PartMesh>(std::move(m));
        link.parent_joint = static_cast<int>(model.joints.size());
        model.links.push_back(std::move(link));
        model.joints.push_back(j);
    }
    // The model frame: the closed model's box centred on x = y = 0, its bottom at z = 0.
    Eigen::AlignedBox3f box;
    const auto poses = model.LinkPoses(model.ClosedState());
    for (std::size_t l = 0; l < model.links.size(); ++l) {
        for (const auto& v : model.links[l].mesh->mesh.vertices) box.extend(poses[l] * v);
    }
    const Eigen::Vector3f c = box.center();
    model.T_model_root =
        Eigen::Translation3f(-c.x(), -c.y(), -box.min().z()) * Eigen::Isometry3f::Identity();
    model.bounds = Eigen::AlignedBox3f(box.min() - Eigen::Vector3f(c.x(), c.y(), box.min().z()),
                                       box.max() - Eigen::Vector3f(c.x(), c.y(), box.min().z()));
    return model;
}

std::vector<KitchenModelEntry> ProceduralKitchenEntries(int per_kind, std::uint64_t seed,
                                                        bool appliances) {
    if (per_kind < 0 || per_kind > kMaxProceduralPerKind) {
        throw InvalidArgument(
            fmt::format("procedural units: the count per kind must lie in [0, {}], got {}",
                        kMaxProceduralPerKind, per_kind));
    }
    std::vector<std::string> kinds = ProceduralUnitKinds();
    if (appliances) {
        kinds.insert(kinds.end(), ProceduralApplianceKinds().begin(),
                     ProceduralApplianceKinds().end());
    }
    std::vector<KitchenModelEntry> out;
    for (std::size_t k = 0; k < kinds.size(); ++k) {
        const std::string& kind = kinds[k];
        for (int i = 0; i < per_kind; ++i) {
            KitchenModelEntry e;
            e.kind = kind;
            e.procedural = true;
            e.procedural_seed = SubSeed(SubSeed(seed, k), static_cast<std::uint64_t>(i));
            e.id = fmt::format("procedural/{}/{:016x}", kind, e.procedural_seed);
            out.push_back(std::move(e));
        }
    }
    return out;
}

}  // namespace multicue::sim
