#include "multicue/sim/kitchen_scene.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/rng.hpp"

namespace multicue::sim {
namespace {

constexpr float kGap = 0.005f;       // between neighbouring units [m]
constexpr float kWallGap = 0.01f;    // between a unit's back and the wall [m]
constexpr float kTallHeight = 1.2f;  // units at least this tall break the worktop [m]

/// A kitchen being built: the scene plus the bookkeeping that turns into KitchenScene.
struct Builder {
    KitchenScene k;
    StreamRng rng;
    explicit Builder(std::uint64_t seed) : rng(seed, 7) {}

    void AddBox(const Eigen::Vector3f& extents, const Eigen::Vector3f& base_center, Color color,
                KitchenClass cls, const std::string& name) {
        SceneObject o;
        o.mesh = std::make_shared<const PartMesh>(MakeBoxMesh(extents, name));
        o.T_world_object = Eigen::Translation3f(base_center) * Eigen::Isometry3f::Identity();
        o.color = color;
        o.source = name;
        Push(std::move(o), KitchenObjectTruth{-1, -1, cls});
    }

    void Push(SceneObject o, const KitchenObjectTruth& t) {
        o.label = static_cast<std::uint32_t>(k.scene.objects.size() + 1);
        k.scene.objects.push_back(std::move(o));
        k.truth.push_back(t);
    }

    /// Places a model with its back against the wall of `run` (frame: origin on the wall face,
    /// tangent t, inward normal n) at tangent position s (its left edge) and height z.
    int AddModel(std::shared_ptr<const ArticulatedModel> model, const Eigen::Vector3f& T_origin,
                 const Eigen::Vector3f& t, const Eigen::Vector3f& n, float s, float z, int run) {
        const Eigen::Vector3f size = model->bounds.sizes();
        Eigen::Matrix3f R;
        R.col(0) = n;
        R.col(2) = Eigen::Vector3f::UnitZ();
        R.col(1) = R.col(2).cross(R.col(0));
        Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
        T.linear() = R;
        // The model's width runs along its y axis, which is +t or -t: centre it at s + w/2.
        T.translation() = T_origin + t * (s + size.y() / 2) + n * (kWallGap + size.x() / 2) +
                          Eigen::Vector3f(0, 0, z);
        return AddInstance(std::move(model), T, run);
    }

    int AddInstance(std::shared_ptr<const ArticulatedModel> model, const Eigen::Isometry3f& T,
                    int run) {
        KitchenInstance inst;
        inst.name = fmt::format("m{:02}", k.instances.size());
        inst.model = model;
        inst.T_world_model = T;
        inst.q = model->ClosedState();
        inst.run = run;
        const auto poses = model->LinkPoses(inst.q);
        const int index = static_cast<int>(k.instances.size());
        for (std::size_t l = 0; l < model->links.size(); ++l) {
            const ArticulatedLink& link = model->links[l];
            if (!link.mesh) {
                inst.link_object.push_back(-1);
                continue;
            }
            SceneObject o;
            o.mesh = link.mesh;
            o.T_world_object = T * poses[l];
            o.use_vertex_colors = link.mesh->mesh.HasVertexColors();
            o.source = model->id + "/" + link.name;
            o.scale = model->scale;
            inst.link_object.push_back(static_cast<int>(k.scene.objects.size()));
            Push(std::move(o),
                 KitchenObjectTruth{index, static_cast<int>(l), LinkClass(*model, l)});
        }
        k.instances.push_back(std::move(inst));
        return index;
    }

    static KitchenClass LinkClass(const ArticulatedModel& m, std::size_t l) {
        const std::string& s = m.links[l].semantic;
        const bool table = m.kind == "table";
        if (s.find("door") != std::string::npos) return KitchenClass::kDoor;
        if (s == "drawer") return KitchenClass::kDrawer;
        if (s == "knob") return KitchenClass::kKnob;
        if (s.find("body") != std::string::npos && table) return KitchenClass::kTable;
        return KitchenClass::kBody;
    }

    std::shared_ptr<const ArticulatedModel> Pick(const std::vector<KitchenModelEntry>& pool,
                                                 KitchenModelCache& cache) {
        std::vector<const KitchenModelEntry*> procedural, library, all;
        for (const auto& e : pool) {
            (e.procedural ? procedural : library).push_back(&e);
            all.push_back(&e);
        }
        // A draw only where both are offered, so that kitchens of library models stay the same.
        const std::vector<const KitchenModelEntry*>* from = &all;
        if (!procedural.empty() && !library.empty()) {
            from = rng.Uniform() < procedural_share ? &procedural : &library;
        }
        return cache.Get(*(*from)[static_cast<std::size_t>(
            rng.UniformInt(0, static_cast<int>(from->size()) - 1))]);
    }
    float procedural_share = 0.5f;
};

/// The models of each kind that fit a kitchen.
std::map<std::string, std::vector<KitchenModelEntry>> Pools(
    const std::vector<KitchenModelEntry>& library, KitchenModelCache& cache,
    const KitchenSceneParams& p) {
    std::map<std::string, std::vector<KitchenModelEntry>> pools;
    for (const auto& e : library) {
        const auto m = cache.Get(e);
        const Eigen::Vector3f s = m->bounds.sizes();
        if (s.y() > p.max_model_width || s.x() > p.max_model_depth) {
            LogDebug("kitchen: {} ({:.2f} m wide, {:.2f} m deep) not used", e.id, s.y(), s.x());
            continue;
        }
        pools[e.kind].push_back(e);
    }
    return pools;
}

Color RandomGrey(StreamRng& rng, int lo, int hi) {
    const int g = rng.UniformInt(lo, hi);
    const int tint = rng.UniformInt(-8, 8);
    auto c = [](int v) { return static_cast<std::uint8_t>(std::clamp(v, 0, 255)); };
    return Color{c(g + tint), c(g), c(g - tint), 255};
}

}  // namespace

const std::vector<std::string>& KitchenClassNames() {
    static const std::vector<std::string> names = {"none",    "wall", "floor", "ceiling",
                                                   "worktop", "body", "door",  "drawer",
                                                   "handle",  "knob", "table", "object"};
    return names;
}

void KitchenSceneParams::Validate() const {
    auto fail = [](const char* name, float v) {
        throw InvalidArgument(fmt::format("kitchen scene: {} out of range, got {}", name, v));
    };
    if (!(room_min >= 2.5f) || !(room_max >= room_min) || !(room_max <= 20.0f)) {
        fail("room_min/room_max (need 2.5 <= min <= max <= 20)", room_min);
    }
    if (!(height_min >= 2.1f) || !(height_max >= height_min) || !(height_max <= 5.0f)) {
        fail("height_min/height_max (need 2.1 <= min <= max <= 5)", height_min);
    }
    if (min_runs < 1 || max_runs > 3 || min_runs > max_runs) {
        fail("min_runs/max_runs (need 1 <= min <= max <= 3)", static_cast<float>(min_runs));
    }
    if (!(worktop_thickness > 0.0f) || !(worktop_overhang >= 0.0f)) {
        fail("worktop_thickness", worktop_thickness);
    }
    for (const float c : {wall_cupboard_chance, microwave_chance, table_chance}) {
        if (!(c >= 0.0f && c <= 1.0f)) fail("a chance (need [0, 1])", c);
    }
    if (max_table_objects < 0) fail("max_table_objects", static_cast<float>(max_table_objects));
    if (!(max_model_width > 0.0f) || !(max_model_depth > 0.0f)) {
        fail("max_model_width", max_model_width);
    }
    if (!(procedural_share >= 0.0f && procedural_share <= 1.0f)) {
        fail("procedural_share (need [0, 1])", procedural_share);
    }
}

void KitchenScene::SetJoint(std::size_t k, float value) {
    if (k >= joints.size()) {
        throw InvalidArgument(fmt::format("kitchen: joint {} out of range ({})", k, joints.size()));
    }
    KitchenInstance& inst = instances[static_cast<std::size_t>(joints[k].instance)];
    inst.q[static_cast<std::size_t>(joints[k].joint)] = value;
    const auto poses = inst.model->LinkPoses(inst.q);
    for (std::size_t l = 0; l < poses.size(); ++l) {
        if (inst.link_object[l] < 0) continue;
        scene.objects[static_cast<std::size_t>(inst.link_object[l])].T_world_object =
            inst.T_world_model * poses[l];
    }
    for (KitchenJoint& j : joints) {
        if (j.instance != joints[k].instance) continue;
        const ArticulatedJoint& aj = inst.model->joints[static_cast<std::size_t>(j.joint)];
        const Eigen::Isometry3f T =
            inst.T_world_model * poses[static_cast<std::size_t>(aj.parent)] * aj.T_parent_joint;
        j.axis_point = T.translation();
        j.axis_direction = T.linear() * aj.axis;
    }
}

int KitchenScene::FindJoint(const std::string& name) const {
    for (std::size_t i = 0; i < joints.size(); ++i) {
        if (joints[i].name == name) return static_cast<int>(i);
    }
    return -1;
}

KitchenScene MakeKitchenScene(const std::vector<KitchenModelEntry>& library,
                              KitchenModelCache& cache, const KitchenSceneParams& p,
                              std::uint64_t seed) {
    p.Validate();
    auto pools = Pools(library, cache, p);
    auto pool = [&](const std::string& kind) -> const std::vector<KitchenModelEntry>& {
        static const std::vector<KitchenModelEntry> none;
        const auto it = pools.find(kind);
        return it == pools.end() ? none : it->second;
    };
    const std::vector<std::string> lower_kinds = {"cupboard",   "sink_cupboard", "drawer_unit",
                                                  "dishwasher", "oven",          "fridge"};
    const std::vector<float> lower_weights = {3.0f, 1.0f, 1.5f, 1.0f, 1.0f, 0.7f};
    bool any_lower = false;
    for (const auto& kind : lower_kinds) any_lower = any_lower || !pool(kind).empty();
    if (!any_lower) throw DataError("kitchen: the library has no lower units");

    Builder b(seed);
    b.procedural_share = p.procedural_share;
    StreamRng& rng = b.rng;
    KitchenScene& k = b.k;
    k.size = Eigen::Vector3f(static_cast<float>(rng.Uniform(p.room_min, p.room_max)),
                             static_cast<float>(rng.Uniform(p.room_min, p.room_max)),
                             static_cast<float>(rng.Uniform(p.height_min, p.height_max)));
    const float Lx = k.size.x(), Ly = k.size.y(), H = k.size.z();
    const Color wall = RandomGrey(rng, 205, 240);
    b.AddBox({Lx + 0.2f, 0.1f, H}, {Lx / 2, Ly + 0.05f, 0}, wall, KitchenClass::kWall, "wall");
    b.AddBox({0.1f, Ly + 0.2f, H}, {-0.05f, Ly / 2, 0}, wall, KitchenClass::kWall, "wall");
    b.AddBox({0.1f, Ly + 0.2f, H}, {Lx + 0.05f, Ly / 2, 0}, wall, KitchenClass::kWall, "wall");
    b.AddBox({Lx + 0.2f, 0.1f, H}, {Lx / 2, -0.05f, 0}, wall, KitchenClass::kWall, "wall");
    b.AddBox({Lx + 0.2f, Ly + 0.2f, 0.05f}, {Lx / 2, Ly / 2, -0.05f}, RandomGrey(rng, 90, 170),
             KitchenClass::kFloor, "floor");
    b.AddBox({Lx + 0.2f, Ly + 0.2f, 0.05f}, {Lx / 2, Ly / 2, H}, RandomGrey(rng, 235, 250),
             KitchenClass::kCeiling, "ceiling");
    const Color worktop_colors[] = {
        {70, 70, 75, 255}, {160, 120, 80, 255}, {225, 222, 215, 255}, {120, 110, 100, 255}};
    const Color worktop = worktop_colors[rng.UniformInt(0, 3)];

    // Runs: the back wall always, then left and/or right.
    const int n_runs = rng.UniformInt(p.min_runs, p.max_runs);
    std::vector<int> walls = {0};
    if (n_runs == 3) {
        walls = {0, 1, 2};
    } else if (n_runs == 2) {
        walls.push_back(rng.UniformInt(1, 2));
    }
    int sinks = 0, dishwashers = 0, ovens = 0, fridges = 0;
    float back_depth = 0.7f;
    for (std::size_t r = 0; r < walls.size(); ++r) {
        Eigen::Vector3f origin, t, n;
        float begin = 0.0f, end = 0.0f;
        if (walls[r] == 0) {  // back wall y = Ly, running along +x
            origin = {0, Ly, 0};
            t = {1, 0, 0};
            n = {0, -1, 0};
            end = Lx;
        } else if (walls[r] == 1) {  // left wall x = 0, running along -y from the back corner
            origin = {0, Ly, 0};
            t = {0, -1, 0};
            n = {1, 0, 0};
            begin = back_depth + 0.03f;
            end = Ly - 0.6f;
        } else {  // right wall x = Lx, running along -y
            origin = {Lx, Ly, 0};
            t = {0, -1, 0};
            n = {-1, 0, 0};
            begin = back_depth + 0.03f;
            end = Ly - 0.6f;
        }
        k.runs.push_back(KitchenScene::Run{origin, t, n, begin, end, 0.0f});
        const int run = static_cast<int>(r);
        // A tall unit (tall cupboard or fridge) now and then at the open end of a side run or
        // the far end of the back run.
        struct Placed {
            float s0, s1, height, depth;
        };
        std::vector<Placed> placed;
        float s = begin;
        std::shared_ptr<const ArticulatedModel> tall;
        if (rng.Uniform() < 0.4) {
            const bool fridge = fridges == 0 && !pool("fridge").empty() && rng.Uniform() < 0.5;
            const auto& tp = fridge ? pool("fridge") : pool("tall_cupboard");
            if (!tp.empty()) {
                tall = b.Pick(tp, cache);
                if (fridge) ++fridges;
            }
        }
        const float reserved = tall ? tall->bounds.sizes().y() + kGap : 0.0f;
        for (int guard = 0; guard < 50; ++guard) {
            const float room = end - reserved - s;
            // Kinds still allowed, weighted; a kind whose models are all too wide drops out.
            std::vector<std::pair<std::string, float>> options;
            for (std::size_t i = 0; i < lower_kinds.size(); ++i) {
                const std::string& kind = lower_kinds[i];
                if ((kind == "sink_cupboard" && sinks > 0) ||
                    (kind == "dishwasher" && dishwashers > 0) || (kind == "oven" && ovens > 0) ||
                    (kind == "fridge" && fridges > 0)) {
                    continue;
                }
                bool fits = false;
                for (const auto& e : pool(kind)) {
                    const auto m = cache.Get(e);
                    fits = fits ||
                           (m->bounds.sizes().y() <= room && m->bounds.sizes().z() < kTallHeight);
                }
                if (fits) options.emplace_back(kind, lower_weights[i]);
            }
            if (options.empty()) break;
            float total = 0.0f;
            for (const auto& o : options) total += o.second;
            float x = static_cast<float>(rng.Uniform()) * total;
            std::string kind = options.back().first;
            for (const auto& o : options) {
                if (x < o.second) {
                    kind = o.first;
                    break;
                }
                x -= o.second;
            }
            std::vector<KitchenModelEntry> fitting;
            for (const auto& e : pool(kind)) {
                const auto m = cache.Get(e);
                if (m->bounds.sizes().y() <= room && m->bounds.sizes().z() < kTallHeight) {
                    fitting.push_back(e);
                }
            }
            const auto model = b.Pick(fitting, cache);
            const Eigen::Vector3f size = model->bounds.sizes();
            b.AddModel(model, origin, t, n, s, 0.0f, run);
            placed.push_back({s, s + size.y(), size.z(), size.x()});
            sinks += kind == "sink_cupboard";
            dishwashers += kind == "dishwasher";
            ovens += kind == "oven";
            fridges += kind == "fridge";
            s += size.y() + kGap;
        }
        if (tall) {
            const float s_tall = std::max(s, end - tall->bounds.sizes().y());
            b.AddModel(tall, origin, t, n, s_tall, 0.0f, run);
        }
        if (placed.empty()) continue;
        // The worktop over the lower units; the back run's depth leaves room in the corners.
        float depth = 0.0f, height = 0.0f;
        for (const auto& pl : placed) {
            depth = std::max(depth, pl.depth);
            height = std::max(height, pl.height);
        }
        if (walls[r] == 0) back_depth = depth + p.worktop_overhang;
        k.runs.back().depth = depth;
        const float s0 = placed.front().s0, s1 = placed.back().s1;
        const float wd = depth + p.worktop_overhang + kWallGap;
        const Eigen::Vector3f c =
            origin + t * ((s0 + s1) / 2) + n * (wd / 2) + Eigen::Vector3f(0, 0, height);
        const Eigen::Vector3f ext = t.cwiseAbs() * (s1 - s0) + n.cwiseAbs() * wd +
                                    Eigen::Vector3f(0, 0, p.worktop_thickness);
        b.AddBox(ext, c, worktop, KitchenClass::kWorktop, "worktop");
        const float worktop_top = height + p.worktop_thickness;
        // A microwave on the worktop, against the wall.
        if (!pool("microwave").empty() && rng.Uniform() < p.microwave_chance) {
            const auto mw = b.Pick(pool("microwave"), cache);
            const float w = mw->bounds.sizes().y();
            if (s1 - s0 > w + 0.2f) {
                const float sm = static_cast<float>(rng.Uniform(s0 + 0.05f, s1 - w - 0.05f));
                b.AddModel(mw, origin, t, n, sm, worktop_top, run);
            }
        }
        // Wall cupboards above the worktop, side by side with now and then a gap.
        const auto& wp = pool("wall_cupboard");
        if (!wp.empty()) {
            float sw = s0;
            for (int guard = 0; guard < 20 && sw < s1; ++guard) {
                const auto wc = b.Pick(wp, cache);
                const Eigen::Vector3f ws = wc->bounds.sizes();
                if (sw + ws.y() > s1) break;
                if (rng.Uniform() < p.wall_cupboard_chance) {
                    const float bottom = std::min(p.wall_cupboard_bottom, H - ws.z() - 0.05f);
                    if (bottom > worktop_top + 0.35f) {
                        b.AddModel(wc, origin, t, n, sw, bottom, run);
                    }
                    sw += ws.y() + kGap;
                } else {
                    sw += 0.3f;
                }
            }
        }
    }

    // A table with objects in the free middle of the room.
    if (!pool("table").empty() && rng.Uniform() < p.table_chance) {
        const auto table = b.Pick(pool("table"), cache);
        const Eigen::Vector3f ts = table->bounds.sizes();
        const float x0 = walls.size() == 3 || (walls.size() == 2 && walls[1] == 1) ? 1.0f : 0.4f;
        const float x1 =
            walls.size() == 3 || (walls.size() == 2 && walls[1] == 2) ? Lx - 1.0f : Lx - 0.4f;
        const float y0 = 0.4f, y1 = Ly - back_depth - 0.8f;
        if (x1 - x0 > ts.y() + 0.2f && y1 - y0 > ts.x() + 0.2f) {
            Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
            T.linear() = Eigen::AngleAxisf(static_cast<float>(std::numbers::pi / 2),
                                           Eigen::Vector3f::UnitZ())
                             .toRotationMatrix();  // front towards +y, long side along x
            T.translation() = Eigen::Vector3f((x0 + x1) / 2, (y0 + y1) / 2, 0.0f);
            b.AddInstance(table, T, -1);
            const float top = ts.z();
            const int n_obj = rng.UniformInt(0, p.max_table_objects);
            std::vector<Eigen::Vector2f> spots;
            for (int o = 0; o < n_obj; ++o) {
                const auto& cats = TabletopCategories();
                ProceduralObject obj =
                    MakeProceduralObject(cats[static_cast<std::size_t>(rng.UniformInt(0, 5))], rng);
                const Eigen::Vector2f xy(static_cast<float>(rng.Uniform(-0.35, 0.35)) * ts.y(),
                                         static_cast<float>(rng.Uniform(-0.3, 0.3)) * ts.x());
                bool free = true;
                for (const auto& q : spots) free = free && (q - xy).norm() > 0.25f;
                if (!free) continue;
                spots.push_back(xy);
                SceneObject so;
                so.mesh = std::make_shared<const PartMesh>(std::move(obj.mesh));
                so.T_world_object =
                    Eigen::Translation3f(T.translation() + Eigen::Vector3f(xy.x(), xy.y(), top)) *
                    Eigen::Isometry3f::Identity();
                so.category = static_cast<std::uint32_t>(CategoryIndex(obj.category));
                so.color = RandomGrey(rng, 40, 220);
                so.source = obj.kind;
                b.Push(std::move(so), KitchenObjectTruth{-1, -1, KitchenClass::kObject});
            }
        }
    }

    // Every movable joint, with its axis in the world.
    for (std::size_t i = 0; i < k.instances.size(); ++i) {
        const KitchenInstance& inst = k.instances[i];
        for (std::size_t j = 0; j < inst.model->joints.size(); ++j) {
            const ArticulatedJoint& aj = inst.model->joints[j];
            if (!aj.Movable()) continue;
            KitchenJoint kj;
            kj.name = inst.name + "__" + aj.name;
            kj.instance = static_cast<int>(i);
            kj.joint = static_cast<int>(j);
            const KitchenClass c =
                Builder::LinkClass(*inst.model, static_cast<std::size_t>(aj.child));
            kj.front = c == KitchenClass::kDoor || c == KitchenClass::kDrawer;
            kj.type = aj.type;
            kj.lower = aj.lower;
            kj.upper = aj.upper;
            k.joints.push_back(kj);
        }
    }
    for (std::size_t j = 0; j < k.joints.size(); ++j) {
        k.SetJoint(j, k.instances[static_cast<std::size_t>(k.joints[j].instance)]
                          .q[static_cast<std::size_t>(k.joints[j].joint)]);
    }
    k.scene.support_center = Eigen::Vector3f(Lx / 2, Ly / 2, 0.9f);
    return k;
}

}  // namespace multicue::sim
