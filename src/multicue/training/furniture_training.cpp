#include "multicue/training/furniture_training.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/filters/voxel_grid.hpp"
#include "multicue/mapping/furniture_detection.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/sim/raycaster.hpp"
#include "multicue/sim/rng.hpp"

namespace multicue::training {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

float Median(std::vector<float> v) {
    if (v.empty()) return 0.0f;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

}  // namespace

const char* FurnitureSensorName(FurnitureSensor sensor) {
    return sensor == FurnitureSensor::kLaser ? "laser" : "kinect";
}

FurnitureSensor ParseFurnitureSensor(const std::string& name) {
    if (name == "laser") return FurnitureSensor::kLaser;
    if (name == "kinect") return FurnitureSensor::kKinect;
    throw InvalidArgument(fmt::format("sensor must be laser or kinect, got '{}'", name));
}

const std::map<std::string, float>& DefaultFurnitureThresholds() {
    // The thesis's working points (tables 1.0, chairs 0.6, sideboards 1.4; section 4.2.5.1);
    // cabinets as tables.
    static const std::map<std::string, float> t = {
        {"table", 1.0f}, {"chair", 0.6f}, {"cabinet", 1.0f}, {"sideboard", 1.4f}};
    return t;
}

void FurnitureTrainingOptions::Validate() const {
    if (furniture.empty() && kitchen.empty() && procedural_per_class <= 0) {
        throw InvalidArgument("furniture training: no library folder and no procedural pieces");
    }
    if (procedural_per_class < 0) {
        throw InvalidArgument(fmt::format(
            "furniture training: procedural_per_class must be >= 0, got {}", procedural_per_class));
    }
    views.Validate();
    parts.Validate();
    vocabulary.Validate();
    if (!(cad_spacing > 0.0f) || !std::isfinite(cad_spacing)) {
        throw InvalidArgument(
            fmt::format("furniture training: cad_spacing must be > 0, got {}", cad_spacing));
    }
    for (const auto& [name, t] : thresholds) {
        if (!(t >= 0.0f) || !std::isfinite(t)) {
            throw InvalidArgument(
                fmt::format("furniture training: threshold of {} must be >= 0, got {}", name, t));
        }
    }
    if (num_threads < 0) throw InvalidArgument("furniture training: num_threads must be >= 0");
    if (verifier_rooms < 0) {
        throw InvalidArgument(
            fmt::format("furniture training: verifier_rooms must be >= 0, got {}", verifier_rooms));
    }
    if (verifier_library_rooms < 0) {
        throw InvalidArgument(
            fmt::format("furniture training: verifier_library_rooms must be >= 0, got {}",
                        verifier_library_rooms));
    }
    if (verifier_fit_models < 1) {
        throw InvalidArgument(fmt::format(
            "furniture training: verifier_fit_models must be >= 1, got {}", verifier_fit_models));
    }
    if (verifier_rooms > 0) {
        (void)ml::CreateClassifier(verifier_spec);  // throws for a bad spec
        verifier_fit.Validate();
    }
}

std::vector<sim::FurniturePiece> FurnitureTrainingPieces(const FurnitureTrainingOptions& o) {
    o.Validate();
    std::vector<sim::FurniturePiece> pieces;
    if (!o.furniture.empty() || !o.kitchen.empty()) {
        const auto library =
            sim::SelectFurnitureSplit(sim::ReadFurnitureLibrary(o.furniture, o.kitchen), o.split);
        for (const auto& e : library) {
            try {
                pieces.push_back(sim::LoadFurniturePiece(e));
            } catch (const Error& err) {
                LogWarning("furniture training: skipping {}: {}", e.id, err.what());
            }
        }
    }
    for (const auto& category : sim::FurnitureCategories()) {
        for (int k = 0; k < o.procedural_per_class; ++k) {
            sim::StreamRng rng(sim::SubSeed(o.seed, 7000 + static_cast<std::uint64_t>(k)),
                               std::hash<std::string>{}(category)&0xffff);
            sim::FurniturePiece p = sim::MakeProceduralFurniture(category, rng);
            p.id = fmt::format("procedural/{}/train{}", category, k);
            pieces.push_back(std::move(p));
        }
    }
    return pieces;
}

PointCloud FurnitureCadCloud(const sim::PartMesh& mesh, float spacing) {
    if (!(spacing > 0.0f)) throw InvalidArgument("CAD cloud: spacing must be > 0");
    sim::Scene scene;
    sim::SceneObject o;
    o.mesh = std::make_shared<const sim::PartMesh>(mesh);
    o.label = sim::ObjectLabel(1);
    scene.objects.push_back(o);
    const sim::RayCaster caster(scene);
    const Eigen::AlignedBox3f box = mesh.Bounds();
    const Eigen::Vector3f c = box.center();
    const float r = 0.5f * box.sizes().norm() + 0.1f;
    const float step = spacing / 2;
    PointCloud hits;
    // Parallel rays from 40 directions: 32 around and above the horizon, 8 from straight above
    // and steeply above (the floor hides the underside, as it hides it from the robot).
    std::vector<Eigen::Vector3f> dirs;
    for (int e = 0; e < 4; ++e) {
        const float el = (-5.0f + 20.0f * static_cast<float>(e)) * kPi / 180.0f;
        for (int a = 0; a < 8; ++a) {
            const float az =
                2 * kPi * (static_cast<float>(a) + 0.5f * static_cast<float>(e % 2)) / 8;
            dirs.emplace_back(-std::cos(el) * std::cos(az), -std::cos(el) * std::sin(az),
                              -std::sin(el));
        }
    }
    for (int a = 0; a < 8; ++a) {
        const float el = (a == 0 ? 89.0f : 65.0f) * kPi / 180.0f;
        const float az = 2 * kPi * static_cast<float>(a) / 7;
        dirs.emplace_back(-std::cos(el) * std::cos(az), -std::cos(el) * std::sin(az),
                          -std::sin(el));
    }
    for (const auto& d : dirs) {
        const Eigen::Vector3f u = d.unitOrthogonal(), v = d.cross(u);
        const int n = static_cast<int>(std::ceil(2 * r / step));
        for (int i = 0; i <= n; ++i) {
            for (int j = 0; j <= n; ++j) {
                const Eigen::Vector3f origin =
                    c - r * d + (-r + step * i) * u + (-r + step * j) * v;
                const sim::RayHit h = caster.Intersect(origin, d);
                if (!h.Valid()) continue;
                hits.points.push_back(origin + h.t * d);
                hits.normals.push_back(h.normal);
            }
        }
    }
    hits.width = static_cast<std::uint32_t>(hits.points.size());
    PointCloud out = VoxelGrid(hits, {.leaf_size = spacing, .num_threads = 1});
    PointCloud clean;
    for (std::size_t i = 0; i < out.size(); ++i) {
        if (!out.normals[i].allFinite()) continue;
        clean.points.push_back(out.points[i]);
        clean.normals.push_back(out.normals[i]);
    }
    clean.width = static_cast<std::uint32_t>(clean.points.size());
    return clean;
}

PointCloud ScanFurniture(const sim::RayCaster& caster, const Eigen::Isometry3f& head,
                         const Eigen::Vector3f& target, const FurnitureTrainingOptions& o,
                         std::uint64_t seed, Eigen::Isometry3f& T_world_sensor) {
    if (o.sensor == FurnitureSensor::kLaser) {
        T_world_sensor = head;
        return sim::ScanLaser(caster, head, o.laser, seed);
    }
    T_world_sensor = sim::CameraAtHead(head, target);
    return sim::ScanKinect(caster, T_world_sensor, o.kinect, seed);
}

std::vector<FurnitureTrainingPart> FurnitureTrainingParts(const sim::FurniturePiece& piece, int cls,
                                                          int piece_index,
                                                          const FurnitureTrainingOptions& o) {
    const sim::Scene scene = sim::MakeFurnitureViewScene(piece);
    const sim::RayCaster caster(scene);
    const float h = piece.mesh->Bounds().sizes().z();
    const Eigen::Vector3f centre(0.0f, 0.0f, h / 2);  // p: the object's centre
    const std::uint64_t seed = sim::SubSeed(o.seed, std::hash<std::string>{}(piece.id));
    const auto heads = sim::FurnitureViewHeads(o.views, seed);
    FurniturePartParams pp = o.parts;
    pp.num_threads = 1;
    std::vector<FurnitureTrainingPart> out;
    for (std::size_t v = 0; v < heads.size(); ++v) {
        Eigen::Isometry3f T;
        FurnitureTrainingOptions so = o;
        so.laser.num_threads = so.kinect.num_threads = 1;
        const PointCloud scan =
            ScanFurniture(caster, heads[v], centre, so, sim::SubSeed(seed, 100 + v), T);
        const FurnitureParts parts = ExtractFurnitureParts(scan, T, pp);
        for (const auto& part : parts.parts) {
            FurnitureTrainingPart tp;
            tp.features = part.features;
            tp.cls = cls;
            tp.piece = piece_index;
            tp.view = static_cast<int>(v);
            tp.centre_z = centre.z();
            // d = p - s in the part's bearing frame (section 4.2.3.2).
            tp.offset = Eigen::AngleAxisf(-part.frame_yaw, Eigen::Vector3f::UnitZ()) *
                        (centre - part.centroid);
            if (tp.features.allFinite()) out.push_back(std::move(tp));
        }
    }
    return out;
}

ScannedFurnitureRoom SimulateFurnitureRoom(const sim::FurnitureRoomParams& params,
                                           const sim::FurnitureSource& source, int heads,
                                           const FurnitureTrainingOptions& o, std::uint64_t seed) {
    ScannedFurnitureRoom out;
    out.room = sim::MakeFurnitureRoom(params, source, seed);
    const sim::RayCaster caster(out.room.scene);
    const auto poses = sim::RoomHeadPoses(out.room, heads, o.views.sensor_height, seed);
    FurnitureTrainingOptions so = o;
    so.laser.fov_deg = sim::LaserParams{}.fov_deg;
    for (std::size_t v = 0; v < poses.size(); ++v) {
        Eigen::Isometry3f T;
        const Eigen::Vector3f target(0.0f, 0.0f, 0.6f);
        out.scans.push_back(
            ScanFurniture(caster, poses[v], target, so, sim::SubSeed(seed, 500 + v), T));
        out.T_world_sensor.push_back(T);
    }
    return out;
}

bool TrainFurnitureModel(const std::vector<sim::FurniturePiece>& pieces,
                         const FurnitureTrainingOptions& o, FurnitureModel& out,
                         Progress* progress) {
    o.Validate();
    if (pieces.empty()) throw InvalidArgument("furniture training: no training pieces");
    std::vector<FurnitureClass> classes;
    std::vector<int> piece_class(pieces.size(), -1);
    for (const auto& name : sim::FurnitureCategories()) {
        std::vector<float> w, l, h;
        for (std::size_t i = 0; i < pieces.size(); ++i) {
            if (pieces[i].category != name) continue;
            const Eigen::Vector3f s = pieces[i].mesh->Bounds().sizes();
            w.push_back(std::min(s.x(), s.y()));
            l.push_back(std::max(s.x(), s.y()));
            h.push_back(s.z());
            piece_class[i] = static_cast<int>(classes.size());
        }
        if (w.empty()) continue;
        FurnitureClass c;
        c.name = name;
        c.width = Median(w);
        c.length = Median(l);
        c.height = Median(h);
        const auto t = o.thresholds.find(name);
        c.threshold = t != o.thresholds.end() ? t->second : 1.0f;
        classes.push_back(c);
    }
    std::vector<std::vector<FurnitureTrainingPart>> parts(pieces.size());
    std::vector<FurnitureCad> cads(pieces.size());
    std::atomic<bool> stopped{false};
    ParallelFor(
        pieces.size(), o.num_threads,
        [&](std::size_t i) {
            if (InterruptRequested()) {
                stopped = true;
                return;
            }
            if (piece_class[i] < 0) return;
            parts[i] = FurnitureTrainingParts(pieces[i], piece_class[i], static_cast<int>(i), o);
            FurnitureCad& cad = cads[i];
            cad.id = pieces[i].id;
            cad.cls = piece_class[i];
            cad.cloud = FurnitureCadCloud(*pieces[i].mesh, o.cad_spacing);
            cad.mesh = pieces[i].mesh->mesh;
            cad.mesh.vertex_colors.clear();
            cad.mesh.vertex_normals.clear();
            cad.mesh.vertex_labels.clear();
            cad.extent = pieces[i].mesh->Bounds().sizes();
            if (progress) progress->Advance();
        },
        1);
    if (stopped || InterruptRequested()) return false;
    std::vector<FurnitureTrainingPart> all;
    for (auto& p : parts)
        all.insert(all.end(), std::make_move_iterator(p.begin()), std::make_move_iterator(p.end()));
    if (all.empty()) throw DataError("furniture training: the training views gave no parts");
    std::vector<FurnitureCad> kept;
    for (std::size_t i = 0; i < cads.size(); ++i) {
        if (piece_class[i] >= 0 && !cads[i].cloud.points.empty())
            kept.push_back(std::move(cads[i]));
    }
    FurnitureVocabularyParams vp = o.vocabulary;
    vp.num_threads = o.num_threads;
    FurnitureModel model =
        FurnitureModel::Train(std::move(all), std::move(classes), std::move(kept), o.parts, vp);
    if (o.verifier_rooms > 0) {
        ml::Dataset rows = CollectFurnitureVerifierRows(model, o, progress);
        if (InterruptRequested()) return false;
        AppendFurnitureLibraryVerifierRows(rows, model, pieces, o, progress);
        if (InterruptRequested()) return false;
        model.SetVerifier(FitFurnitureVerifier(model, rows, o));
    }
    out = std::move(model);
    return true;
}

std::shared_ptr<const ml::Classifier> FitFurnitureVerifier(const FurnitureModel& model,
                                                           const ml::Dataset& rows,
                                                           const FurnitureTrainingOptions& o) {
    if (rows.feature_names != FurnitureVerifierFeatureNames(model)) {
        throw DataError(
            "furniture training: the verifier rows have other features than the model's verifier");
    }
    const int right_class = rows.FindClass("right");
    std::size_t right = 0;
    for (int l : rows.labels) right += l == right_class ? 1 : 0;
    if (right == 0 || right == rows.rows()) {
        throw DataError(fmt::format(
            "furniture training: the verifier rows hold {} fits, {} of them right; the verifier "
            "needs right and wrong ones",
            rows.rows(), right));
    }
    std::shared_ptr<ml::Classifier> verifier = ml::CreateClassifier(o.verifier_spec);
    verifier->seed = static_cast<std::uint32_t>(o.seed);
    verifier->Fit(rows);
    return verifier;
}

std::size_t FurnitureTrainingSteps(const std::vector<sim::FurniturePiece>& pieces,
                                   const FurnitureTrainingOptions& options) {
    if (options.verifier_rooms <= 0) return pieces.size();
    return pieces.size() + static_cast<std::size_t>(options.verifier_rooms) +
           FurnitureLibraryVerifierSteps(pieces, options);
}

bool IsProceduralFurniture(const sim::FurniturePiece& piece) {
    return piece.id.rfind("procedural/", 0) == 0;
}

FurnitureLibraryHalves SplitFurnitureLibrary(const std::vector<sim::FurniturePiece>& pieces) {
    FurnitureLibraryHalves out;
    std::map<std::string, std::vector<const sim::FurniturePiece*>> by_class;
    for (const auto& p : pieces) {
        if (IsProceduralFurniture(p)) {
            out.procedural.push_back(p);
        } else {
            by_class[p.category].push_back(&p);
        }
    }
    for (auto& [category, list] : by_class) {
        std::sort(list.begin(), list.end(),
                  [](const auto* a, const auto* b) { return a->id < b->id; });
        for (std::size_t i = 0; i < list.size(); ++i) out.library[i % 2].push_back(*list[i]);
    }
    return out;
}

std::size_t FurnitureLibraryVerifierSteps(const std::vector<sim::FurniturePiece>& pieces,
                                          const FurnitureTrainingOptions& options) {
    if (options.verifier_library_rooms <= 0) return 0;
    std::size_t procedural = 0;
    for (const auto& p : pieces) procedural += IsProceduralFurniture(p) ? 1 : 0;
    if (procedural == 0 || procedural == pieces.size()) return 0;
    // Two stand-ins, each of the procedural pieces and one half of the library.
    return 2 * procedural + (pieces.size() - procedural) +
           static_cast<std::size_t>(options.verifier_library_rooms);
}

namespace {

// Appends to `rows` the fits of `fit_model` in `rooms` rooms furnished from `source` (seeds from
// `first_seed`; offices, seminar rooms and kitchens in turn), the scans merged and each alone,
// every fit labelled right when a true piece of its class stands within half its width of the
// fitted model's centre; features as `model`'s verifier names them. One progress step per room.
void AppendVerifierRows(ml::Dataset& rows, const FurnitureModel& fit_model,
                        const FurnitureModel& model, const sim::FurnitureSource& source,
                        std::uint64_t first_seed, int rooms, const FurnitureTrainingOptions& o,
                        Progress* progress) {
    FurnitureDetectionParams dp;
    // Rows from the hypotheses above the class thresholds (those down to 0.3 of them, which
    // detection fits, gave a slightly worse verifier on the validation rooms: eval/README.md).
    dp.selection.threshold_scale = 1.0f;
    dp.learned = false;
    dp.fit = o.verifier_fit;
    dp.fit_models = o.verifier_fit_models;
    dp.piece.grow = false;  // the label judges the fitted model, which the features describe
    dp.num_threads = o.num_threads;
    const FurnitureFitContext context(fit_model, dp.fit);
    for (int r = 0; r < rooms && !InterruptRequested(); ++r) {
        sim::FurnitureRoomParams rp;
        rp.type = static_cast<sim::RoomType>(r % 3);
        const std::uint64_t seed = first_seed + static_cast<std::uint64_t>(r);
        const ScannedFurnitureRoom room = SimulateFurnitureRoom(rp, source, 3, o, seed);
        std::vector<FurnitureView> views;
        for (std::size_t v = 0; v < room.scans.size(); ++v)
            views.push_back({&room.scans[v], room.T_world_sensor[v]});
        const FurnitureScene scene = PrepareFurnitureScene(views, fit_model, dp);
        std::vector<std::vector<int>> subsets = {{}};
        for (std::size_t v = 0; v < views.size(); ++v) subsets.push_back({static_cast<int>(v)});
        for (const auto& subset : subsets) {
            const FurnitureDetectionResult det =
                DetectFurniture(scene, subset, fit_model, &context, dp);
            std::vector<const FurnitureParts*> parts;  // the subset's, for piece labels
            std::vector<const FurnitureFreeSpace*> free;
            for (std::size_t v = 0; o.verifier_piece_labels && v < scene.views.size(); ++v) {
                if (subset.empty() ||
                    std::find(subset.begin(), subset.end(), static_cast<int>(v)) != subset.end()) {
                    parts.push_back(&scene.views[v]);
                    if (v < scene.free_space.size()) free.push_back(&scene.free_space[v]);
                }
            }
            for (const auto* list : {&det.detections, &det.rejected}) {
                for (const FurnitureDetection& d : *list) {
                    if (!d.fitted) continue;
                    Eigen::AlignedBox3f box;
                    const Eigen::Vector2f centre =
                        o.verifier_piece_labels
                            ? FurniturePieceCentre(
                                  parts, fit_model.cads()[static_cast<std::size_t>(d.fit.cad)],
                                  d.fit, FurniturePieceParams{}, box, free)
                            : d.centre;
                    bool right = false;
                    for (const auto& f : room.room.furniture) {
                        right =
                            right || (f.category == d.category &&
                                      (f.T_world_object.translation().head<2>() - centre).norm() <
                                          f.width / 2);
                    }
                    rows.AppendRow(FurnitureVerifierFeatures(d, model), right ? "right" : "wrong",
                                   static_cast<std::int64_t>(seed));
                }
            }
        }
        if (progress) progress->Advance();
    }
}

ml::Dataset EmptyVerifierRows(const FurnitureModel& model) {
    ml::Dataset rows = ml::Dataset::WithBlocks({{"fit", FurnitureVerifierFeatureNames(model)}});
    rows.ClassId("right");
    rows.ClassId("wrong");
    return rows;
}

}  // namespace

void AppendFurnitureLibraryVerifierRows(ml::Dataset& rows, const FurnitureModel& model,
                                        const std::vector<sim::FurniturePiece>& pieces,
                                        const FurnitureTrainingOptions& o, Progress* progress) {
    o.Validate();
    if (rows.feature_names != FurnitureVerifierFeatureNames(model)) {
        throw InvalidArgument(
            "furniture training: the verifier rows have other features than the model's verifier");
    }
    if (o.verifier_library_rooms <= 0) return;
    const FurnitureLibraryHalves split = SplitFurnitureLibrary(pieces);
    const auto& procedural = split.procedural;
    const auto& halves = split.library;
    if (procedural.empty() || halves[0].empty()) return;
    FurnitureTrainingOptions so = o;
    so.verifier_rooms = 0;
    so.verifier_library_rooms = 0;
    std::uint64_t seed = o.verifier_library_seed;
    for (int h = 0; h < 2; ++h) {
        const int rooms =
            o.verifier_library_rooms / 2 + (h == 0 ? o.verifier_library_rooms % 2 : 0);
        if (halves[h].empty() || rooms == 0) continue;
        // The stand-in: the procedural pieces and the other half of the library.
        std::vector<sim::FurniturePiece> train = procedural;
        train.insert(train.end(), halves[1 - h].begin(), halves[1 - h].end());
        FurnitureModel stand_in;
        if (!TrainFurnitureModel(train, so, stand_in, progress)) return;
        bool same = stand_in.classes().size() == model.classes().size();
        for (std::size_t c = 0; same && c < model.classes().size(); ++c)
            same = stand_in.classes()[c].name == model.classes()[c].name;
        if (!same) {
            throw DataError(
                "furniture training: the procedural pieces do not hold every class of the model");
        }
        const sim::FurnitureSource source(halves[h], 0.0f);
        AppendVerifierRows(rows, stand_in, model, source, seed, rooms, o, progress);
        seed += static_cast<std::uint64_t>(rooms);
    }
}

ml::Dataset CollectFurnitureVerifierRows(const FurnitureModel& model,
                                         const FurnitureTrainingOptions& o, Progress* progress) {
    o.Validate();
    ml::Dataset rows = EmptyVerifierRows(model);
    const sim::FurnitureSource source({}, 1.0f);
    AppendVerifierRows(rows, model, model, source, o.verifier_seed, o.verifier_rooms, o, progress);
    return rows;
}

}  // namespace multicue::training
