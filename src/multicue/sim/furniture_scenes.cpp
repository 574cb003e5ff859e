#include "multicue/sim/furniture_scenes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/objects.hpp"
#include "multicue/sim/placement_internal.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/sim_math_internal.hpp"

namespace multicue::sim {
namespace {

using math_internal::kPi;
using placement_internal::Polygon;

using math_internal::U;

Eigen::Isometry3f Upright(const Eigen::Vector2f& at, float yaw) {
    Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
    T.linear() = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3f(at.x(), at.y(), 0.0f);
    return T;
}

Polygon Footprint(const PartMesh& mesh, const Eigen::Isometry3f& T) {
    Polygon pts;
    pts.reserve(mesh.mesh.vertices.size());
    for (const auto& v : mesh.mesh.vertices) {
        const Eigen::Vector3f w = T * v;
        pts.emplace_back(w.x(), w.y());
    }
    return ConvexHull2D(std::move(pts));
}

// Places pieces in a room of size sx x sy (centred on the origin) without overlaps.
class RoomBuilder {
  public:
    explicit RoomBuilder(FurnitureRoom& room) : room_(room) {}

    // Places `piece` with its canonical origin at `at`, turned by `yaw`, if it stays inside the
    // room and `gap` away from everything placed (joined pieces pass a negative gap).
    bool TryPlace(const FurniturePiece& piece, const Eigen::Vector2f& at, float yaw, float gap,
                  bool furniture = true) {
        const Eigen::Isometry3f T = Upright(at, yaw);
        Polygon poly = Footprint(*piece.mesh, T);
        const Eigen::Vector2f half = room_.size / 2 - Eigen::Vector2f::Constant(0.01f);
        if (!placement_internal::Inside(poly, -half, half)) return false;
        if (placement_internal::MinSeparation(poly, placed_) < gap) return false;
        placed_.push_back(std::move(poly));
        SceneObject o;
        o.mesh = piece.mesh;
        o.T_world_object = T;
        o.label = ObjectLabel(static_cast<std::uint32_t>(++objects_));
        o.category =
            furniture ? static_cast<std::uint32_t>(std::max(0, CategoryIndex(piece.category))) : 0u;
        o.color = color_;
        o.use_vertex_colors = piece.mesh->mesh.HasVertexColors();
        o.source = piece.id;
        o.scale = piece.scale;
        o.placement = ObjectPlacement::kStanding;
        o.support = kFloorLabel;
        room_.scene.objects.push_back(o);
        if (furniture) {
            FurnitureTruth t;
            t.label = o.label;
            t.category = piece.category;
            t.id = piece.id;
            t.T_world_object = T;
            t.yaw = std::remainder(yaw, 2 * kPi);
            t.extent = piece.mesh->Bounds().sizes();
            t.width = FurnitureWidth(*piece.mesh);
            room_.furniture.push_back(t);
        }
        return true;
    }

    // Against wall `w` (0: y = -sy/2, 1: y = +sy/2, 2: x = -sx/2, 3: x = +sx/2), front facing
    // into the room, at `along` [m] from the wall's centre.
    bool AgainstWall(const FurniturePiece& piece, int w, float along, float gap) {
        const Eigen::Vector3f size = piece.mesh->Bounds().sizes();
        const float depth = size.x() / 2 + 0.02f;
        const Eigen::Vector2f half = room_.size / 2;
        Eigen::Vector2f at;
        float yaw = 0.0f;
        switch (w) {
            case 0:
                at = {along, -half.y() + depth};
                yaw = kPi / 2;
                break;
            case 1:
                at = {along, half.y() - depth};
                yaw = -kPi / 2;
                break;
            case 2:
                at = {-half.x() + depth, along};
                yaw = 0.0f;
                break;
            default:
                at = {half.x() - depth, along};
                yaw = kPi;
                break;
        }
        return TryPlace(piece, at, yaw, gap);
    }

    float WallLength(int w) const { return w < 2 ? room_.size.x() : room_.size.y(); }
    void SetColor(StreamRng& rng) { color_ = RandomColor(rng); }

  private:
    FurnitureRoom& room_;
    std::vector<Polygon> placed_;
    int objects_ = 0;
    Color color_{180, 160, 130, 255};
};

// Chairs around a table (yaw `table_yaw`, canonical size `ts`) at `centre`: along both long
// sides (x = +-depth/2 in the table frame), facing it.
void ChairsAround(RoomBuilder& b, const FurniturePiece& chair, const Eigen::Vector2f& centre,
                  float table_yaw, const Eigen::Vector3f& ts, int count, bool ends, float gap,
                  StreamRng& rng) {
    const Eigen::Vector3f cs = chair.mesh->Bounds().sizes();
    const float pitch = cs.y() + U(rng, 0.08f, 0.3f);
    const int per_side = std::max(1, static_cast<int>((ts.y() - 0.1f) / pitch));
    std::vector<std::pair<Eigen::Vector2f, float>> slots;  // table frame position, yaw
    for (int side = -1; side <= 1; side += 2) {
        for (int k = 0; k < per_side; ++k) {
            const float y = -pitch * (per_side - 1) / 2.0f + pitch * k;
            const float x = side * (ts.x() / 2 + cs.x() / 2 + U(rng, 0.05f, 0.25f));
            slots.push_back({{x, y}, side > 0 ? kPi : 0.0f});
        }
    }
    if (ends) {
        for (int side = -1; side <= 1; side += 2) {
            const float y = side * (ts.y() / 2 + cs.x() / 2 + U(rng, 0.05f, 0.25f));
            slots.push_back({{0.0f, y}, side > 0 ? -kPi / 2 : kPi / 2});
        }
    }
    std::shuffle(slots.begin(), slots.end(), rng);
    const Eigen::Rotation2Df R(table_yaw);
    int placed = 0;
    for (const auto& [p, yaw] : slots) {
        if (placed >= count) break;
        const float jitter = U(rng, -0.25f, 0.25f);
        if (b.TryPlace(chair, centre + R * p, table_yaw + yaw + jitter, gap)) ++placed;
    }
}

FurniturePiece Distractor(StreamRng& rng) {
    FurniturePiece d;
    d.source = "procedural";
    d.category = "none";
    const int kind = rng.UniformInt(0, 2);
    PartMesh m;
    if (kind == 0) {  // a bin or box
        const float s = U(rng, 0.25f, 0.6f);
        m = MakeBoxMesh({s, U(rng, 0.25f, 0.6f), U(rng, 0.3f, 0.7f)}, "box");
        d.id = "distractor/box";
    } else if (kind == 1) {  // a person
        const float r = U(rng, 0.15f, 0.22f), h = U(rng, 1.55f, 1.9f);
        m = MakeRevolutionMesh({{0.0f, 0.0f, 0},
                                {r, 0.0f, 0},
                                {r, h - 0.25f, 0},
                                {0.1f, h - 0.2f, 0},
                                {0.1f, h, 0},
                                {0.0f, h, 0}},
                               {"person"}, 16);
        d.id = "distractor/person";
    } else {  // a plant in a pot
        const float r = U(rng, 0.12f, 0.25f);
        m = MakeRevolutionMesh({{0.0f, 0.0f, 0},
                                {r * 0.8f, 0.0f, 0},
                                {r, 0.35f, 0},
                                {r * 2.0f, 0.6f, 0},
                                {r * 1.5f, 1.0f, 0},
                                {0.0f, 1.1f, 0}},
                               {"plant"}, 12);
        d.id = "distractor/plant";
    }
    d.mesh = std::make_shared<const PartMesh>(std::move(m));
    return d;
}

}  // namespace

Scene MakeFurnitureViewScene(const FurniturePiece& piece, float yaw) {
    Scene scene;
    scene.objects.push_back(placement_internal::Floor(6.0f));
    SceneObject o;
    o.mesh = piece.mesh;
    o.T_world_object = Upright(Eigen::Vector2f::Zero(), yaw);
    o.label = ObjectLabel(1);
    o.category = static_cast<std::uint32_t>(std::max(0, CategoryIndex(piece.category)));
    o.use_vertex_colors = piece.mesh->mesh.HasVertexColors();
    o.source = piece.id;
    o.scale = piece.scale;
    o.placement = ObjectPlacement::kStanding;
    o.support = kFloorLabel;
    scene.objects.push_back(o);
    const Eigen::Vector3f size = piece.mesh->Bounds().sizes();
    scene.support_size = size.head<2>();
    scene.support_center = Eigen::Vector3f(0, 0, size.z() / 2);
    return scene;
}

void FurnitureViewParams::Validate() const {
    if (views < 1) throw InvalidArgument(fmt::format("views must be >= 1, got {}", views));
    if (!(min_distance > 0.0f) || !(max_distance >= min_distance) || !std::isfinite(max_distance)) {
        throw InvalidArgument(fmt::format("view distances must satisfy 0 < min <= max, got {}, {}",
                                          min_distance, max_distance));
    }
    if (!(sensor_height > 0.0f) || !std::isfinite(sensor_height)) {
        throw InvalidArgument(fmt::format("sensor_height must be > 0, got {}", sensor_height));
    }
    if (!(azimuth_jitter >= 0.0f) || !std::isfinite(azimuth_jitter)) {
        throw InvalidArgument(fmt::format("azimuth_jitter must be >= 0, got {}", azimuth_jitter));
    }
}

std::vector<Eigen::Isometry3f> FurnitureViewHeads(const FurnitureViewParams& p,
                                                  std::uint64_t seed) {
    p.Validate();
    std::vector<Eigen::Isometry3f> poses;
    for (int k = 0; k < p.views; ++k) {
        StreamRng rng(seed, static_cast<std::uint64_t>(k));
        const float a = 2 * kPi * static_cast<float>(k) / static_cast<float>(p.views) +
                        U(rng, -p.azimuth_jitter, p.azimuth_jitter);
        const float r = U(rng, p.min_distance, p.max_distance);
        Eigen::Isometry3f T = Upright(Eigen::Vector2f(r * std::cos(a), r * std::sin(a)), a + kPi);
        T.translation().z() = p.sensor_height;
        poses.push_back(T);
    }
    return poses;
}

Eigen::Isometry3f CameraAtHead(const Eigen::Isometry3f& head, const Eigen::Vector3f& target) {
    return LookAt(head.translation(), target);
}

FurnitureSource::FurnitureSource(std::vector<FurniturePiece> library, float procedural_share)
    : procedural_share_(procedural_share) {
    for (auto& p : library) pieces_[p.category].push_back(std::move(p));
}

bool FurnitureSource::HasLibrary(const std::string& category) const {
    const auto it = pieces_.find(category);
    return it != pieces_.end() && !it->second.empty();
}

FurniturePiece FurnitureSource::Random(const std::string& category, StreamRng& rng) const {
    const bool procedural = rng.Uniform() < procedural_share_ || !HasLibrary(category);
    const std::uint64_t n = rng();
    if (!procedural) {
        const auto& v = pieces_.at(category);
        return v[n % v.size()];
    }
    StreamRng prng(n);
    FurniturePiece piece = MakeProceduralFurniture(category, prng);
    piece.id = fmt::format("procedural/{}/{:016x}", category, n);
    return piece;
}

const char* RoomTypeName(RoomType type) {
    switch (type) {
        case RoomType::kOffice:
            return "office";
        case RoomType::kSeminar:
            return "seminar";
        case RoomType::kKitchen:
            return "kitchen";
    }
    return "office";
}

RoomType ParseRoomType(std::string_view name) {
    if (name == "office") return RoomType::kOffice;
    if (name == "seminar") return RoomType::kSeminar;
    if (name == "kitchen") return RoomType::kKitchen;
    throw InvalidArgument(
        fmt::format("room type must be office, seminar or kitchen, got '{}'", name));
}

void FurnitureRoomParams::Validate() const {
    if (max_distractors < 0) {
        throw InvalidArgument(fmt::format("max_distractors must be >= 0, got {}", max_distractors));
    }
    if (!(wall_height > 0.5f) || !std::isfinite(wall_height)) {
        throw InvalidArgument(fmt::format("wall_height must be > 0.5 m, got {}", wall_height));
    }
    if (!(min_gap >= 0.0f) || !std::isfinite(min_gap)) {
        throw InvalidArgument(fmt::format("min_gap must be >= 0, got {}", min_gap));
    }
}

FurnitureRoom MakeFurnitureRoom(const FurnitureRoomParams& p, const FurnitureSource& source,
                                std::uint64_t seed) {
    p.Validate();
    StreamRng rng(seed, 0);
    FurnitureRoom room;
    room.type = p.type;
    const bool seminar = p.type == RoomType::kSeminar;
    room.size = seminar ? Eigen::Vector2f(U(rng, 6.0f, 9.0f), U(rng, 5.0f, 7.0f))
                        : Eigen::Vector2f(U(rng, 4.0f, 6.5f), U(rng, 3.5f, 5.5f));
    const float sx = room.size.x(), sy = room.size.y();
    placement_internal::AddFloorAndWalls(sx, sy, p.wall_height, room.scene);
    room.scene.support_size = room.size;
    RoomBuilder b(room);
    const float gap = p.min_gap;
    auto random_wall_spot = [&](const FurniturePiece& piece, int tries) {
        for (int k = 0; k < tries; ++k) {
            const int w = rng.UniformInt(0, 3);
            const float len = b.WallLength(w) / 2 - piece.mesh->Bounds().sizes().y() / 2 - 0.05f;
            if (len <= 0.0f) continue;
            if (b.AgainstWall(piece, w, U(rng, -len, len), gap)) return true;
        }
        return false;
    };
    auto free_spot = [&](const FurniturePiece& piece, float margin, int tries) {
        for (int k = 0; k < tries; ++k) {
            const Eigen::Vector2f at(U(rng, -sx / 2 + margin, sx / 2 - margin),
                                     U(rng, -sy / 2 + margin, sy / 2 - margin));
            if (b.TryPlace(piece, at, U(rng, -kPi, kPi), gap)) return true;
        }
        return false;
    };
    b.SetColor(rng);
    if (p.type == RoomType::kOffice) {
        const int desks = rng.UniformInt(1, 2);
        for (int d = 0; d < desks; ++d) {
            const FurniturePiece desk = source.Random("table", rng);
            const FurniturePiece chair = source.Random("chair", rng);
            const Eigen::Vector3f ds = desk.mesh->Bounds().sizes();
            for (int k = 0; k < 30; ++k) {
                const int w = rng.UniformInt(0, 3);
                const float len = b.WallLength(w) / 2 - ds.y() / 2 - 0.05f;
                if (len <= 0.0f || !b.AgainstWall(desk, w, U(rng, -len, len), gap)) continue;
                const auto& T = room.furniture.back().T_world_object;
                // Chairs in front of the desk (its +x side), facing it.
                const int chairs = rng.UniformInt(1, 2);
                for (int c = 0; c < chairs; ++c) {
                    const Eigen::Vector3f cs = chair.mesh->Bounds().sizes();
                    const float span = std::max(0.0f, ds.y() / 2 - cs.y() / 2);
                    const Eigen::Vector3f local(ds.x() / 2 + cs.x() / 2 + U(rng, 0.05f, 0.35f),
                                                U(rng, -span, span), 0.0f);
                    const Eigen::Vector3f at = T * local;
                    b.TryPlace(chair, at.head<2>(),
                               room.furniture.back().yaw + kPi + U(rng, -0.4f, 0.4f), gap);
                }
                break;
            }
        }
        const int storage = rng.UniformInt(1, 3);
        for (int k = 0; k < storage; ++k) {
            random_wall_spot(source.Random(rng.Uniform() < 0.7 ? "cabinet" : "sideboard", rng), 30);
        }
        if (rng.Uniform() < 0.4) free_spot(source.Random("chair", rng), 0.5f, 30);
    } else if (seminar) {
        // Rows of identical tables (apart: joined tops would be one part) with the chairs
        // behind them facing the front, and storage along the walls.
        const FurniturePiece table = source.Random("table", rng);
        const FurniturePiece chair = source.Random("chair", rng);
        const Eigen::Vector3f ts = table.mesh->Bounds().sizes(), cs = chair.mesh->Bounds().sizes();
        const float yaw = (rng.Uniform() < 0.5 ? 0.0f : kPi / 2) + U(rng, -0.08f, 0.08f);
        const Eigen::Rotation2Df R(yaw);
        const int rows = rng.UniformInt(2, 3), per_row = rng.UniformInt(1, 3);
        const float row_pitch = ts.x() + cs.x() + U(rng, 0.5f, 0.9f);
        const float gap_y = U(rng, 0.25f, 0.6f);
        const Eigen::Vector2f centre(U(rng, -0.3f, 0.3f), U(rng, -0.3f, 0.3f));
        for (int r = 0; r < rows; ++r) {
            const float x = (static_cast<float>(r) - (rows - 1) / 2.0f) * row_pitch + cs.x() / 2;
            for (int k = 0; k < per_row; ++k) {
                const float y = (static_cast<float>(k) - (per_row - 1) / 2.0f) * (ts.y() + gap_y);
                if (!b.TryPlace(table, centre + R * Eigen::Vector2f(x, y), yaw, gap)) continue;
                const int chairs =
                    std::max(1, std::min(3, static_cast<int>(ts.y() / (cs.y() + 0.15f))));
                const float pitch = ts.y() / static_cast<float>(chairs);
                for (int c = 0; c < chairs; ++c) {
                    if (rng.Uniform() < 0.15) continue;  // an empty place
                    const Eigen::Vector2f local(
                        x - ts.x() / 2 - cs.x() / 2 - U(rng, 0.05f, 0.25f),
                        y - ts.y() / 2 + pitch * (static_cast<float>(c) + 0.5f));
                    b.TryPlace(chair, centre + R * local, yaw + U(rng, -0.3f, 0.3f), gap);
                }
            }
        }
        const int storage = rng.UniformInt(0, 2);
        for (int k = 0; k < storage; ++k) {
            random_wall_spot(source.Random(rng.Uniform() < 0.5 ? "cabinet" : "sideboard", rng), 30);
        }
    } else {  // kitchen
        const int w = rng.UniformInt(0, 3);
        const int cupboards = rng.UniformInt(2, 4);
        float along = -b.WallLength(w) / 2 + 0.1f + U(rng, 0.0f, 0.5f);
        for (int k = 0; k < cupboards; ++k) {
            const FurniturePiece c = source.Random("cabinet", rng);
            const float cw = c.mesh->Bounds().sizes().y();
            if (along + cw > b.WallLength(w) / 2 - 0.05f) break;
            // Apart: the fronts of cupboards in a closed row would be one part.
            b.AgainstWall(c, w, along + cw / 2, gap);
            along += cw + U(rng, 0.1f, 0.6f);
        }
        const FurniturePiece table = source.Random("table", rng);
        const FurniturePiece chair = source.Random("chair", rng);
        for (int k = 0; k < 30; ++k) {
            const Eigen::Vector2f at(U(rng, -sx / 4, sx / 4), U(rng, -sy / 4, sy / 4));
            const float yaw = U(rng, -kPi, kPi);
            if (!b.TryPlace(table, at, yaw, 0.6f)) continue;
            ChairsAround(b, chair, at, yaw, table.mesh->Bounds().sizes(), rng.UniformInt(2, 4),
                         rng.Uniform() < 0.3, gap, rng);
            break;
        }
        if (rng.Uniform() < 0.5) random_wall_spot(source.Random("sideboard", rng), 30);
    }
    const int distractors = rng.UniformInt(0, p.max_distractors);
    for (int k = 0; k < distractors; ++k) {
        const FurniturePiece d = Distractor(rng);
        for (int tries = 0; tries < 30; ++tries) {
            const Eigen::Vector2f at(U(rng, -sx / 2 + 0.3f, sx / 2 - 0.3f),
                                     U(rng, -sy / 2 + 0.3f, sy / 2 - 0.3f));
            if (b.TryPlace(d, at, U(rng, -kPi, kPi), 0.2f, false)) break;
        }
    }
    return room;
}

std::vector<Eigen::Isometry3f> RoomHeadPoses(const FurnitureRoom& room, int count, float height,
                                             std::uint64_t seed) {
    if (count < 1) throw InvalidArgument(fmt::format("head count must be >= 1, got {}", count));
    if (!(height > 0.0f))
        throw InvalidArgument(fmt::format("head height must be > 0, got {}", height));
    StreamRng rng(seed, 21);
    std::vector<Polygon> feet;
    for (const auto& o : room.scene.objects) {
        if (o.label < ObjectLabel(1)) continue;
        feet.push_back(Footprint(*o.mesh, o.T_world_object));
    }
    const Eigen::Vector2f half = room.size / 2 - Eigen::Vector2f::Constant(0.5f);
    std::vector<Eigen::Vector2f> free;
    for (float x = -half.x(); x <= half.x(); x += 0.2f) {
        for (float y = -half.y(); y <= half.y(); y += 0.2f) {
            const Polygon dot = {
                {x - 0.01f, y - 0.01f}, {x + 0.01f, y - 0.01f}, {x + 0.01f, y + 0.01f}};
            if (placement_internal::MinSeparation(dot, feet) >= 0.4f) free.emplace_back(x, y);
        }
    }
    if (free.empty()) free.emplace_back(0.0f, 0.0f);
    // Farthest-point sampling from a random start spreads the heads over the room.
    std::vector<Eigen::Vector2f> picked = {free[rng() % free.size()]};
    while (static_cast<int>(picked.size()) < count) {
        float best = -1.0f;
        Eigen::Vector2f best_p = free.front();
        for (const auto& f : free) {
            float d = std::numeric_limits<float>::infinity();
            for (const auto& q : picked) d = std::min(d, (f - q).norm());
            d *= U(rng, 0.8f, 1.0f);
            if (d > best) best = d, best_p = f;
        }
        picked.push_back(best_p);
    }
    std::vector<Eigen::Isometry3f> poses;
    for (const auto& at : picked) {
        const float yaw = std::atan2(-at.y(), -at.x()) + U(rng, -0.4f, 0.4f);
        Eigen::Isometry3f T = Upright(at, yaw);
        T.translation().z() = height;
        poses.push_back(T);
    }
    return poses;
}

}  // namespace multicue::sim
