// Part-graph hashing in simulated clutter (docs/part-graph.md): trains on procedural objects and
// (when present) every other mesh of a mesh library, tests on table scenes with 3-8 partly
// touching objects from the other meshes (procedural objects without a library), six views per
// scene. Prints per-point and per-part accuracy with a confusion matrix, the rule-based
// categoriser's per-point accuracy on the same points, the multi-view gain (5 mm voxel votes) and
// the time to categorise all parts of a 640x480 frame.
//
// usage: part_graph_eval [--meshes DIR] [--scenes N] [--seed S] [--max-meshes N]
//                        [--size-weight W] [--balanced 0|1] [--k K] [--max-parts N]
//                        [--table-scenes N] [--table-views N] [--objects N] [--train-meshes 0|1]
//                        [--blend-weight W]

#include <chrono>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>

#include "multicue/core/exceptions.hpp"
#include "multicue/recognition/part_graph_model.hpp"
#include "multicue/sim/mesh.hpp"
#include "multicue/sim/objects.hpp"
#include "multicue/sim/raycaster.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "multicue/surface/normals.hpp"
#include "multicue/system/perceive.hpp"
#include "part_graph_training.hpp"

using namespace multicue;

namespace {

struct Counts {
    std::array<std::array<std::size_t, kNumCategories>, kNumCategories> m{};
    void Add(int truth, int pred) { ++m[truth][pred]; }
    double Accuracy() const {
        std::size_t ok = 0, all = 0;
        for (std::size_t t = 1; t < kNumCategories; ++t)
            for (std::size_t p = 0; p < kNumCategories; ++p) {
                all += m[t][p];
                if (t == p) ok += m[t][p];
            }
        return all ? double(ok) / double(all) : 0.0;
    }
    std::size_t Total() const {
        std::size_t all = 0;
        for (std::size_t t = 1; t < kNumCategories; ++t)
            for (auto v : m[t]) all += v;
        return all;
    }
};

void PrintConfusion(const char* title, const Counts& c) {
    std::printf("%s (rows truth, columns predicted; accuracy %.3f over %zu)\n", title, c.Accuracy(),
                c.Total());
    std::printf("%10s", "");
    for (std::size_t p = 0; p < kNumCategories; ++p) std::printf("%9s", kCategoryNames[p].data());
    std::printf("\n");
    for (std::size_t t = 1; t < kNumCategories; ++t) {
        std::printf("%10s", kCategoryNames[t].data());
        for (std::size_t p = 0; p < kNumCategories; ++p) std::printf("%9zu", c.m[t][p]);
        std::printf("\n");
    }
}

}  // namespace

int main(int argc, char** argv) {
    std::string meshes = std::string(MULTICUE_SHARED_DATA_DIR) + "/meshes/tabletop";
    int scenes = 4, max_meshes = 60;
    std::uint64_t seed = 1;
    PartGraphModel model;
    PartGraphRecognitionParams rp;
    float blend_weight = 0.2f;
    int table_scenes = training::PartGraphTrainingOptions{}.table_scenes, table_views = 4,
        objects = 8, train_meshes = 1;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--meshes"))
            meshes = argv[i + 1];
        else if (!std::strcmp(argv[i], "--scenes"))
            scenes = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--seed"))
            seed = std::strtoull(argv[i + 1], nullptr, 10);
        else if (!std::strcmp(argv[i], "--max-meshes"))
            max_meshes = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--size-weight"))
            model.descriptor_params.size_weight = std::strtof(argv[i + 1], nullptr);
        else if (!std::strcmp(argv[i], "--balanced"))
            rp.balanced = std::atoi(argv[i + 1]) != 0;
        else if (!std::strcmp(argv[i], "--k"))
            rp.k = std::strtoull(argv[i + 1], nullptr, 10);
        else if (!std::strcmp(argv[i], "--max-parts"))
            rp.max_parts = std::strtoull(argv[i + 1], nullptr, 10);
        else if (!std::strcmp(argv[i], "--table-scenes"))
            table_scenes = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--table-views"))
            table_views = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--blend-weight"))
            blend_weight = std::strtof(argv[i + 1], nullptr);
        else if (!std::strcmp(argv[i], "--objects"))
            objects = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--train-meshes"))
            train_meshes = std::atoi(argv[i + 1]);
    }
    const bool library = std::filesystem::exists(std::filesystem::path(meshes) / "labels.csv");
    training::PartGraphTrainingOptions o;
    o.seed = seed;
    o.objects_per_category = objects;
    o.table_scenes = table_scenes;
    o.table_views = table_views;
    if (library) {
        o.meshes = meshes;
        o.mesh_modulo = 2;
        o.mesh_remainder = 0;
        o.max_meshes = max_meshes;
        o.mesh_turntable = train_meshes != 0;
    }
    auto t0 = std::chrono::steady_clock::now();
    training::TrainPartGraphModel(model, o);
    const double train_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fflush(stdout);
    std::printf(
        "training: %zu subgraphs, %zu buckets, %.1f s (%d procedural objects per category, %s, "
        "%d table scenes x %d views; size weight %g, %s votes)\n",
        model.num_rows(), model.num_buckets(), train_s, objects,
        library && train_meshes ? "even library meshes" : "no library meshes", table_scenes,
        table_views, double(model.descriptor_params.size_weight),
        rp.balanced ? "balanced" : "plain");

    std::optional<sim::ObjectSource> source;
    if (library) {
        auto all = sim::ReadMeshLibrary(meshes, sim::TabletopCategories());
        std::vector<sim::MeshEntry> test;
        for (std::size_t i = 1; i < all.size(); i += 2) test.push_back(all[i]);
        source.emplace(std::move(test), false);
    } else {
        source.emplace();
    }
    PerceiveParams pp;
    Counts point, part, rules, multi, single_in_multi, blend;
    double recog_ms = 0.0;
    std::size_t frames = 0, parts_total = 0;
    sim::TableSceneParams sp;
    sp.clutter = 0.6f;
    for (int s = 0; s < scenes; ++s) {
        const sim::Scene scene = sim::MakeTableScene(sp, *source, seed * 1000 + s);
        const sim::RayCaster caster(scene);
        const auto views = sim::TableViewpoints(scene, 6, {}, seed * 1000 + s);
        VoxelVoteGrid grid(0.005f);
        std::vector<std::pair<std::vector<Eigen::Vector3f>, std::vector<int>>> kept;
        std::vector<std::vector<Category>> single;
        for (std::size_t v = 0; v < views.size(); ++v) {
            PointCloud scan = sim::ScanKinect(caster, views[v], {}, seed * 7919 + s * 10 + v);
            const auto* gt_field = scan.FindExtraField("category");
            if (!gt_field) throw DataError("scan without category field");
            {  // normals as perceive computes them; perceive keeps them
                OrganizedNormalParams np = pp.organized_normals;
                SetNormals(scan, EstimateNormalsOrganized(scan, np));
            }
            const PerceiveResult r = Perceive(scan, pp);
            std::vector<Indices> parts;
            std::vector<std::size_t> part_object;
            for (std::size_t ob = 0; ob < r.objects.size(); ++ob)
                for (const auto& p : r.objects[ob].parts) {
                    parts.push_back(p);
                    part_object.push_back(ob);
                }
            const auto a = std::chrono::steady_clock::now();
            const PartGraphResult pg = RecognizeParts(model, scan, parts, rp);
            recog_ms +=
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a)
                    .count();
            ++frames;
            parts_total += parts.size();
            // part-graph+rules per object (as perceive blends them).
            std::vector<std::vector<std::size_t>> ids(r.objects.size());
            for (std::size_t k = 0; k < parts.size(); ++k) ids[part_object[k]].push_back(k);
            for (std::size_t ob = 0; ob < r.objects.size(); ++ob) {
                const auto& c = r.objects[ob].category;
                Category cat = c.category;
                if (cat != Category::kNone && !ids[ob].empty()) {
                    cat = ArgMaxCategory(BlendCategoryProbabilities(
                        c.probabilities, MergePartProbabilities(pg, parts, ids[ob]), blend_weight));
                }
                for (std::size_t k : ids[ob])
                    for (Index i : parts[k]) {
                        const int t = gt_field->data[i];
                        if (t >= 1 && t < static_cast<int>(kNumCategories))
                            blend.Add(t, static_cast<int>(cat));
                    }
            }
            std::vector<Eigen::Vector3f> world;
            std::vector<std::array<float, kNumCategories>> votes;
            std::vector<int> truth;
            std::vector<Category> pred;
            for (std::size_t k = 0; k < parts.size(); ++k) {
                std::array<std::size_t, kNumCategories> hist{};
                for (Index i : parts[k]) {
                    const int t = gt_field->data[i];
                    if (t < 1 || t >= static_cast<int>(kNumCategories)) continue;
                    ++hist[t];
                    point.Add(t, static_cast<int>(pg.part_categories[k]));
                    rules.Add(t, r.point_categories[i]);
                    world.push_back(views[v] * scan.points[i]);
                    votes.push_back(pg.part_probabilities[k]);
                    truth.push_back(t);
                    pred.push_back(pg.part_categories[k]);
                }
                const auto best = std::max_element(hist.begin(), hist.end()) - hist.begin();
                if (hist[best] > 0) part.Add(static_cast<int>(best), int(pg.part_categories[k]));
            }
            grid.Add(world, votes);
            kept.emplace_back(std::move(world), std::move(truth));
            single.push_back(std::move(pred));
        }
        for (std::size_t v = 0; v < kept.size(); ++v) {
            for (std::size_t i = 0; i < kept[v].first.size(); ++i) {
                multi.Add(kept[v].second[i], static_cast<int>(grid.CategoryAt(kept[v].first[i])));
                single_in_multi.Add(kept[v].second[i], static_cast<int>(single[v][i]));
            }
        }
        std::printf("scene %d: %zu objects, %zu frames done\n", s, scene.objects.size(), frames);
        std::fflush(stdout);
    }
    PrintConfusion("per point, part-graph hashing", point);
    PrintConfusion("per part (segment), part-graph hashing", part);
    PrintConfusion("per point, rule-based categoriser (perceive default)", rules);
    std::printf("per point, part-graph+rules (weight %.2f): %.3f\n", double(blend_weight),
                blend.Accuracy());
    std::printf("multi-view (6 views, 5 mm voxel votes): %.3f per point vs %.3f single views\n",
                multi.Accuracy(), single_in_multi.Accuracy());
    std::printf(
        "categorising all parts of a 640x480 frame: %.1f ms mean over %zu frames "
        "(%.1f parts per frame; graph, GRSD- and votes; 1 thread)\n",
        recog_ms / double(std::max<std::size_t>(frames, 1)), frames,
        double(parts_total) / double(std::max<std::size_t>(frames, 1)));
    return 0;
}
