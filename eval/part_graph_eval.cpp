// Part-graph hashing in simulated clutter (docs/part-graph.md): trains on procedural objects and
// (when present) every other mesh of a mesh library, tests on table scenes with 3-8 partly
// touching objects from the other meshes (procedural objects without a library), six views per
// scene. Prints per-point and per-part accuracy with a confusion matrix, the rule-based
// categoriser's per-point accuracy on the same points, the multi-view gain (5 mm voxel votes) and
// the time to categorise all parts of a 640x480 frame. Baselines on the same parts and points
// (thesis Table 5.9), trained on the same training objects: a vocabulary of parts (k-means words
// of the model's mapped part descriptor and of the 24 statistical part features; part votes
// through the words' categories, and bag-of-words histograms of objects classified by
// --object-classifier) and a classifier of whole clusters (GRSD- and VFH). Per point and per
// perceived object (truth: the majority category of its points), with confusion matrices and
// the per-scene spread.
//
// usage: part_graph_eval [--meshes DIR] [--scenes N] [--seed S] [--max-meshes N]
//                        [--size-weight W] [--balanced 0|1] [--k K] [--max-parts N]
//                        [--table-scenes N] [--table-views N] [--objects N] [--train-meshes 0|1]
//                        [--blend-weight W] [--baselines 0|1] [--words N] [--activations N]
//                        [--object-classifier SPEC] [--cluster-size-weight W] [--matrices 0|1]
//                        [--scene-matrices 0|1]
//                        [--grsd-weight W] [--elevation-weight W] [--rsd-weight W]
//                        [--extent-weights A,B,C] [--upright-extents 0|1] [--variants
//                        "k=10;ew=2,rw=1;..."] [--stacker-scenes N] [--stacker-views N]
//                        [--dump FILE.csv] [--even-test 0|1] [--procedural-test 0|1]
//                        [--expert-weights R,P,C]
//
// --table-scenes defaults to what multicue train takes: 40, or 80 when the model trains on library
// meshes. --stacker-scenes trains the model's stacker (row "stacked"). --dump writes one CSV row
// per perceived object: seed, scene, view, source mesh, truth, points, the six probabilities of the
// rules, the part-graph and the whole-object expert, the rules' six scores and their geometric
// evidence (CategoryResult: extents, height, box score, axis area, planar part ratio, cylinder
// side / cap / coverage / radius, sphere ratio / radius, footprint fill, side face ratio,
// upright). --even-test tests on scenes of the training meshes, --procedural-test on procedural
// objects (both for fitting combinations of the experts outside the test objects).
//
// The main rows recognise and blend as perceive does by default (PerceiveParams: the perceived
// objects as part groups, its category priors and part-graph weight; --blend-weight overrides the
// weight). --variants: further part-graph settings on the same parts, each counted three times
// (part labels, object labels, object labels blended with the rules). Recognition keys k, dw,
// off, se, mp, cw, bal, wo (only subgraphs inside one perceived object, 0|1), ow (weight of each
// whole object's own vote) and the category priors ps, pb, pf, pc, pp, po (sphere, box, flat,
// cylinder, plate, other); descriptor keys gw, ew, rw, sw (GRSD-, elevation, curvature, size
// weight), e1, e2, e3 (extent factors) and ue (upright extents 0|1), which train a further model
// from the same training rows, graphs and sampling seeds.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "multicue/core/exceptions.hpp"
#include "multicue/features/part_stats.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/recognition/part_graph_model.hpp"
#include "multicue/recognition/part_vocabulary.hpp"
#include "multicue/sim/mesh.hpp"
#include "multicue/sim/objects.hpp"
#include "multicue/sim/raycaster.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "multicue/surface/normals.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/training/part_graph_training.hpp"

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

// One categoriser's counts: per point, per perceived object, per point in each scene.
struct Method {
    std::string name;
    Counts point, object, scene;
    std::vector<double> scene_accuracy;
    void EndScene() {
        if (scene.Total() > 0) scene_accuracy.push_back(scene.Accuracy());
        scene = {};
    }
    void AddPoint(int truth, Category pred) {
        point.Add(truth, static_cast<int>(pred));
        scene.Add(truth, static_cast<int>(pred));
    }
};

std::pair<double, double> MeanStd(const std::vector<double>& v) {
    if (v.empty()) return {0.0, 0.0};
    double m = 0.0;
    for (double x : v) m += x;
    m /= double(v.size());
    double s = 0.0;
    for (double x : v) s += (x - m) * (x - m);
    return {m, v.size() > 1 ? std::sqrt(s / double(v.size() - 1)) : 0.0};
}

// A classifier of whole objects from one feature row per training object.
struct ObjectClassifier {
    std::unique_ptr<ml::Classifier> classifier;
    void Fit(const std::vector<FeatureVector>& rows, const std::vector<Category>& labels,
             const std::string& spec) {
        ml::Dataset d = ml::Dataset::WithColumns(static_cast<std::size_t>(rows.at(0).size()));
        for (std::size_t i = 0; i < rows.size(); ++i) {
            d.AppendRow({rows[i].data(), static_cast<std::size_t>(rows[i].size())},
                        std::string(kCategoryNames[static_cast<std::size_t>(labels[i])]));
        }
        classifier = ml::CreateClassifier(spec);
        classifier->Fit(d);
    }
    Category Predict(const FeatureVector& row) const {
        const ml::FeatureMatrix x = row.transpose();
        const int c = classifier->Predict(x).at(0);
        return ParseCategory(classifier->class_names().at(static_cast<std::size_t>(c)));
    }
};

// Stored form of every part (row) with a voxel of its own; `keep` marks which rows qualified.
FeatureMatrix MappedParts(const PartGraphModel& model, const FeatureMatrix& raw,
                          std::vector<bool>* keep = nullptr) {
    FeatureMatrix out(raw.rows(), kPartMappedSize);
    Eigen::Index n = 0;
    if (keep) keep->assign(static_cast<std::size_t>(raw.rows()), false);
    for (Eigen::Index i = 0; i < raw.rows(); ++i) {
        float grsd = 0.0f;
        for (int j = 0; j < kPartGrsdSize; ++j) grsd += raw(i, j);
        if (grsd <= 0.0f) continue;
        model.MapDescriptor(raw.row(i).data(), out.row(n++).data());
        if (keep) (*keep)[static_cast<std::size_t>(i)] = true;
    }
    out.conservativeResize(n, kPartMappedSize);
    return out;
}

// Rows of `m` whose statistics are defined (not all zero).
FeatureMatrix DefinedRows(const FeatureMatrix& m, std::vector<bool>* keep = nullptr) {
    FeatureMatrix out(m.rows(), m.cols());
    Eigen::Index n = 0;
    if (keep) keep->assign(static_cast<std::size_t>(m.rows()), false);
    for (Eigen::Index i = 0; i < m.rows(); ++i) {
        if (m.row(i).cwiseAbs().sum() <= 0.0f) continue;
        out.row(n++) = m.row(i);
        if (keep) (*keep)[static_cast<std::size_t>(i)] = true;
    }
    out.conservativeResize(n, m.cols());
    return out;
}

// A vocabulary of parts over one part feature and its bag-of-words object classifier.
struct VocabularyBaseline {
    PartVocabulary vocabulary;
    ObjectClassifier objects;
    std::size_t train_parts = 0;
};

VocabularyBaseline TrainVocabulary(const std::vector<FeatureMatrix>& object_parts,
                                   const std::vector<Category>& labels,
                                   const PartVocabularyParams& vp, const std::string& spec) {
    VocabularyBaseline b;
    std::size_t total = 0;
    for (const auto& m : object_parts) total += static_cast<std::size_t>(m.rows());
    FeatureMatrix all(static_cast<Eigen::Index>(total), object_parts.at(0).cols());
    std::vector<Category> cats;
    Eigen::Index r = 0;
    for (std::size_t o = 0; o < object_parts.size(); ++o) {
        for (Eigen::Index i = 0; i < object_parts[o].rows(); ++i) {
            all.row(r++) = object_parts[o].row(i);
            cats.push_back(labels[o]);
        }
    }
    b.train_parts = total;
    b.vocabulary = PartVocabulary::Train(all, cats, vp);
    std::vector<FeatureVector> bows;
    std::vector<Category> bow_labels;
    for (std::size_t o = 0; o < object_parts.size(); ++o) {
        if (object_parts[o].rows() == 0) continue;
        bows.push_back(b.vocabulary.BagOfWords(object_parts[o]));
        bow_labels.push_back(labels[o]);
    }
    b.objects.Fit(bows, bow_labels, spec);
    return b;
}

}  // namespace

int main(int argc, char** argv) {
    std::string meshes = std::string(MULTICUE_SHARED_DATA_DIR) + "/meshes/tabletop";
    int scenes = 4, max_meshes = 0;  // 0: every even-indexed mesh
    std::uint64_t seed = 1;
    PartGraphModel model;
    // Recognition and blend as perceive runs them (parts grouped by object, its category priors).
    PartGraphRecognitionParams rp = CategorizationParams{}.part_graph;
    float blend_weight = CategorizationParams{}.part_graph_weight;
    int baselines = 1, matrices = 1;
    bool scene_matrices = false;
    PartVocabularyParams vp;
    vp.words = 200;
    vp.num_threads = 0;
    std::string object_spec = "knn:k=5";
    std::string variants;
    int stacker_scenes = 0, stacker_views = 6;  // held-out scenes training the stacker
    bool even_test = false;        // test scenes of the training meshes (seen instances)
    bool procedural_test = false;  // test scenes of procedural objects even with a library
    std::string dump_path;  // one CSV row per perceived object: truth, experts, rule evidence
    Eigen::Vector3f expert_weights = CategorizationParams{}.expert_weights;
    ClusterDescriptorParams cluster_params;
    int table_scenes = -1, table_views = 4,  // table scenes -1: as multicue train
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
        else if (!std::strcmp(argv[i], "--baselines"))
            baselines = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--stacker-scenes"))
            stacker_scenes = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--stacker-views"))
            stacker_views = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--even-test"))
            even_test = std::atoi(argv[i + 1]) != 0;
        else if (!std::strcmp(argv[i], "--procedural-test"))
            procedural_test = std::atoi(argv[i + 1]) != 0;
        else if (!std::strcmp(argv[i], "--dump"))
            dump_path = argv[i + 1];
        else if (!std::strcmp(argv[i], "--matrices"))
            matrices = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--scene-matrices"))
            scene_matrices = std::atoi(argv[i + 1]) != 0;
        else if (!std::strcmp(argv[i], "--words"))
            vp.words = std::strtoull(argv[i + 1], nullptr, 10);
        else if (!std::strcmp(argv[i], "--activations"))
            vp.activations = std::strtoull(argv[i + 1], nullptr, 10);
        else if (!std::strcmp(argv[i], "--variants"))
            variants = argv[i + 1];
        else if (!std::strcmp(argv[i], "--distance-weighted"))
            rp.distance_weighted = std::atoi(argv[i + 1]) != 0;
        else if (!std::strcmp(argv[i], "--size-exponent"))
            rp.size_exponent = std::strtof(argv[i + 1], nullptr);
        else if (!std::strcmp(argv[i], "--object-classifier"))
            object_spec = argv[i + 1];
        else if (!std::strcmp(argv[i], "--grsd-weight"))
            model.descriptor_params.grsd_weight = std::strtof(argv[i + 1], nullptr);
        else if (!std::strcmp(argv[i], "--elevation-weight"))
            model.descriptor_params.elevation_weight = std::strtof(argv[i + 1], nullptr);
        else if (!std::strcmp(argv[i], "--upright-extents"))
            model.descriptor_params.upright_extents = std::atoi(argv[i + 1]) != 0;
        else if (!std::strcmp(argv[i], "--rsd-weight"))
            model.descriptor_params.rsd_weight = std::strtof(argv[i + 1], nullptr);
        else if (!std::strcmp(argv[i], "--extent-weights")) {
            auto& e = model.descriptor_params.extent_weights;
            if (std::sscanf(argv[i + 1], "%f,%f,%f", &e[0], &e[1], &e[2]) != 3) {
                std::fprintf(stderr, "--extent-weights needs A,B,C\n");
                return 2;
            }
        } else if (!std::strcmp(argv[i], "--expert-weights")) {
            auto& w = expert_weights;
            if (std::sscanf(argv[i + 1], "%f,%f,%f", &w[0], &w[1], &w[2]) != 3) {
                std::fprintf(stderr, "--expert-weights needs R,P,C\n");
                return 2;
            }
        } else if (!std::strcmp(argv[i], "--cluster-size-weight"))
            cluster_params.size_weight = std::strtof(argv[i + 1], nullptr);
        else {
            std::fprintf(stderr, "unknown option %s\n", argv[i]);
            return 2;
        }
    }
    const bool library = std::filesystem::exists(std::filesystem::path(meshes) / "labels.csv");
    if (table_scenes < 0) {
        table_scenes = library && train_meshes ? training::kLibraryTableScenes
                                               : training::PartGraphTrainingOptions{}.table_scenes;
    }
    training::PartGraphTrainingOptions o;
    o.seed = seed;
    o.objects_per_category = objects;
    o.table_scenes = table_scenes;
    o.table_views = table_views;
    o.stacker_scenes = stacker_scenes;
    o.stacker_views = stacker_views;
    if (library) {
        o.meshes = meshes;
        o.mesh_modulo = 2;
        o.mesh_remainder = 0;
        o.max_meshes = max_meshes;
        o.mesh_turntable = train_meshes != 0;
    }
    std::vector<training::TrainingObject> train_objects;
    const bool descriptor_variants =
        variants.find("gw=") != std::string::npos || variants.find("ew=") != std::string::npos ||
        variants.find("rw=") != std::string::npos || variants.find("sw=") != std::string::npos ||
        variants.find("e1=") != std::string::npos || variants.find("e2=") != std::string::npos ||
        variants.find("e3=") != std::string::npos || variants.find("ue=") != std::string::npos;
    if (baselines || descriptor_variants) o.objects_out = &train_objects;
    if (baselines) {
        o.cluster_params = cluster_params;
        o.part_statistics = true;
    }
    auto t0 = std::chrono::steady_clock::now();
    training::TrainPartGraphModel(model, o);
    const double train_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fflush(stdout);
    std::printf(
        "training: %zu subgraphs, %zu buckets, %.1f s (%d procedural objects per category, %s, "
        "%d table scenes x %d views; size weight %g, extents x %g %g %g, GRSD- %g, elevation %g, "
        "curvature %g, %s extents, %s votes)\n",
        model.num_rows(), model.num_buckets(), train_s, objects,
        library && train_meshes ? "even library meshes" : "no library meshes", table_scenes,
        table_views, double(model.descriptor_params.size_weight),
        double(model.descriptor_params.extent_weights[0]),
        double(model.descriptor_params.extent_weights[1]),
        double(model.descriptor_params.extent_weights[2]),
        double(model.descriptor_params.grsd_weight),
        double(model.descriptor_params.elevation_weight),
        double(model.descriptor_params.rsd_weight),
        model.descriptor_params.upright_extents ? "upright" : "principal",
        rp.balanced ? "balanced" : "plain");
    if (model.stacker.trained()) {
        std::printf("stacker: %zu perceived objects of %d held-out scenes x %d views\n",
                    model.stacker.train_rows(), stacker_scenes, stacker_views);
    }

    // Baselines trained on the same objects.
    VocabularyBaseline vocab_model, vocab_stats;
    ObjectClassifier whole;
    if (baselines) {
        t0 = std::chrono::steady_clock::now();
        std::vector<FeatureMatrix> mapped, stats;
        std::vector<Category> labels;
        std::vector<FeatureVector> clusters;
        for (const auto& t : train_objects) {
            mapped.push_back(MappedParts(model, t.part_descriptors));
            stats.push_back(DefinedRows(t.part_statistics));
            labels.push_back(t.category);
            clusters.push_back(t.cluster);
        }
        vocab_model = TrainVocabulary(mapped, labels, vp, object_spec);
        PartVocabularyParams sp = vp;
        sp.normalize = true;
        vocab_stats = TrainVocabulary(stats, labels, sp, object_spec);
        whole.Fit(clusters, labels, object_spec);
        std::printf(
            "baselines: %zu training objects, %zu / %zu parts, %zu words, %zu activations, object "
            "classifier %s, %.1f s\n",
            train_objects.size(), vocab_model.train_parts, vocab_stats.train_parts,
            vocab_model.vocabulary.num_words(), vp.activations, object_spec.c_str(),
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    enum {
        kPg,
        kPgRules,
        kRules,
        kPgObject,
        kFusion3,
        kStacked,
        kVocabModelParts,
        kVocabModelBow,
        kVocabStatsParts,
        kVocabStatsBow,
        kWhole,
        kNumMethods
    };
    std::vector<Method> methods(kNumMethods);
    methods[kPg].name = "part-graph hashing";
    char blend_name[64];
    std::snprintf(blend_name, sizeof blend_name, "part-graph+rules (weight %.2f)",
                  double(blend_weight));
    methods[kPgRules].name = blend_name;
    methods[kRules].name = "rule-based categoriser (perceive default)";
    methods[kPgObject].name = "part-graph hashing, object categories (as perceive labels)";
    methods[kVocabModelParts].name = "vocabulary of parts, model descriptor, part votes";
    methods[kVocabModelBow].name = "vocabulary of parts, model descriptor, bag of words";
    methods[kVocabStatsParts].name = "vocabulary of parts, 24 part statistics, part votes";
    methods[kVocabStatsBow].name = "vocabulary of parts, 24 part statistics, bag of words";
    methods[kWhole].name = "whole cluster, GRSD- + VFH";
    methods[kFusion3].name = "part-graph+rules+cluster (rules x part-graph x model's cluster k-NN)";
    methods[kStacked].name = "stacked (level-1 classifier over the three experts)";
    int num_methods = baselines ? int(kNumMethods) : int(kVocabModelParts);
    // Further part-graph recognition settings on the same model and parts ("k=10,dw=1;se=0.5").
    std::vector<PartGraphRecognitionParams> variant_params;
    std::vector<std::shared_ptr<const PartGraphModel>> variant_models;
    {
        std::size_t begin = 0;
        while (begin < variants.size()) {
            std::size_t end = variants.find(';', begin);
            if (end == std::string::npos) end = variants.size();
            const std::string spec = variants.substr(begin, end - begin);
            begin = end + 1;
            if (spec.empty()) continue;
            PartGraphRecognitionParams vr = rp;
            PartDescriptorParams vd = model.descriptor_params;
            bool own_model = false;
            std::size_t b = 0;
            while (b < spec.size()) {
                std::size_t e = spec.find(',', b);
                if (e == std::string::npos) e = spec.size();
                const std::string kv = spec.substr(b, e - b);
                b = e + 1;
                const auto eq = kv.find('=');
                if (eq == std::string::npos) {
                    std::fprintf(stderr, "bad variant %s\n", kv.c_str());
                    return 2;
                }
                const std::string key = kv.substr(0, eq);
                const double val = std::strtod(kv.c_str() + eq + 1, nullptr);
                if (key == "k")
                    vr.k = std::size_t(val);
                else if (key == "dw")
                    vr.distance_weighted = val != 0.0;
                else if (key == "off")
                    vr.distance_offset = float(val);
                else if (key == "se")
                    vr.size_exponent = float(val);
                else if (key == "mp")
                    vr.max_parts = std::size_t(val);
                else if (key == "cw")
                    vr.confidence_weighted = val != 0.0;
                else if (key == "bal")
                    vr.balanced = val != 0.0;
                else if (key == "wo")
                    vr.within_groups = val != 0.0;
                else if (key == "ow")
                    vr.group_weight = float(val);
                else if (key.size() == 2 && key[0] == 'p') {  // prior: ps, pb, pf, pc, pp, po
                    const std::string_view ids = "sbfcpo";
                    const auto at = ids.find(key[1]);
                    if (at == std::string_view::npos) {
                        std::fprintf(stderr, "bad variant key %s\n", key.c_str());
                        return 2;
                    }
                    vr.category_priors[at + 1] = float(val);
                } else if (key == "ue") {
                    own_model = true;
                    vd.upright_extents = val != 0.0;
                } else if (key == "gw" || key == "ew" || key == "rw" || key == "sw" ||
                           key == "e1" || key == "e2" || key == "e3") {
                    own_model = true;
                    float& w = key == "gw"   ? vd.grsd_weight
                               : key == "ew" ? vd.elevation_weight
                               : key == "rw" ? vd.rsd_weight
                               : key == "sw" ? vd.size_weight
                               : key == "e1" ? vd.extent_weights[0]
                               : key == "e2" ? vd.extent_weights[1]
                                             : vd.extent_weights[2];
                    w = float(val);
                } else {
                    std::fprintf(stderr, "bad variant key %s\n", key.c_str());
                    return 2;
                }
            }
            variant_params.push_back(vr);
            if (own_model) {
                auto vm = std::make_shared<PartGraphModel>();
                vm->graph_params = model.graph_params;
                vm->descriptor_params = vd;
                for (const auto& t : train_objects) {
                    PartGraphTrainParams tp = o.train;
                    tp.seed = t.train_seed;
                    vm->AddObject(t.part_descriptors, t.graph, t.category, tp);
                }
                vm->Build();
                variant_models.push_back(std::move(vm));
            } else {
                variant_models.push_back(nullptr);
            }
            methods.push_back({});
            methods.back().name = "part-graph " + spec;
            methods.push_back({});
            methods.back().name = "part-graph " + spec + ", object labels";
            methods.push_back({});
            methods.back().name = "part-graph " + spec + ", +rules";
        }
    }
    // Three rows per variant: part labels, each object's merged label, that blended with the
    // rules (--blend-weight).
    constexpr int kVariantRows = 3;
    const int first_variant = int(methods.size()) - kVariantRows * int(variant_params.size());
    const auto skip = [&](int m) {
        return (m >= num_methods && m < first_variant) ||
               (m == kStacked && !model.stacker.trained());
    };

    std::optional<sim::ObjectSource> source;
    if (library && !procedural_test) {
        auto all = sim::ReadMeshLibrary(meshes, sim::TabletopCategories());
        std::vector<sim::MeshEntry> test;
        for (std::size_t i = even_test ? 0 : 1; i < all.size(); i += 2) test.push_back(all[i]);
        source.emplace(std::move(test), false);
    } else {
        source.emplace();
    }
    PerceiveParams pp;
    CategorizationParams expert_params = pp.category;  // the experts as perceive runs them
    expert_params.part_graph = rp;
    expert_params.expert_weights = expert_weights;
    std::FILE* dump = dump_path.empty() ? nullptr : std::fopen(dump_path.c_str(), "w");
    if (!dump_path.empty() && !dump) {
        std::fprintf(stderr, "cannot write %s\n", dump_path.c_str());
        return 2;
    }
    Counts part, multi, single_in_multi;
    Counts ceiling;  // every perceived object named by the majority truth of its points
    Counts multi_obj, single_obj;      // votes with each object's distribution (as perceive fuses)
    Counts multi_prod;                 // the same votes as log(p + 0.01) - log(0.01): product rule
    Counts multi_three, single_three;  // object votes of part-graph+rules+cluster
    double recog_ms = 0.0;
    std::size_t frames = 0, parts_total = 0;
    sim::TableSceneParams sp;
    sp.clutter = 0.6f;
    for (int s = 0; s < scenes; ++s) {
        const sim::Scene scene = sim::MakeTableScene(sp, *source, seed * 1000 + s);
        const sim::RayCaster caster(scene);
        const auto views = sim::TableViewpoints(scene, 6, {}, seed * 1000 + s);
        VoxelVoteGrid grid(0.005f), grid_obj(0.005f), grid_prod(0.005f), grid_three(0.005f);
        std::vector<std::pair<std::vector<Eigen::Vector3f>, std::vector<int>>> kept;
        std::vector<std::vector<Category>> single, single_o, single_3;
        for (std::size_t v = 0; v < views.size(); ++v) {
            PointCloud scan = sim::ScanKinect(caster, views[v], {}, seed * 7919 + s * 10 + v);
            const auto* gt_field = scan.FindExtraField("category");
            if (!gt_field) throw DataError("scan without category field");
            {  // normals as perceive computes them; perceive keeps them
                OrganizedNormalParams np = pp.normals.organized;
                SetNormals(scan, EstimateNormalsOrganized(scan, np));
            }
            const PerceiveResult r = Perceive(scan, pp);
            std::vector<Indices> parts;
            std::vector<std::uint32_t> part_object;  // also the recognition's part groups
            for (std::size_t ob = 0; ob < r.objects.size(); ++ob)
                for (const auto& p : r.objects[ob].parts) {
                    parts.push_back(p);
                    part_object.push_back(static_cast<std::uint32_t>(ob));
                }
            const auto a = std::chrono::steady_clock::now();
            const PartGraph graph = BuildPartGraph(scan, parts, model.graph_params);
            // Up as perceive knows it: the support plane's normal (camera -y without one).
            const Eigen::Vector3f up = r.support.found ? Eigen::Vector3f(r.support.plane.head<3>())
                                                       : Eigen::Vector3f::Zero();
            const FeatureMatrix raw =
                ComputePartDescriptors(scan, parts, model.descriptor_params, up);
            const PartGraphResult pg = RecognizeParts(model, graph, raw, rp, part_object);
            recog_ms +=
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a)
                    .count();
            ++frames;
            parts_total += parts.size();
            // Per-part predictions of every method (object-level methods: the object's).
            std::vector<std::vector<Category>> part_pred(
                parts.size(), std::vector<Category>(methods.size(), Category::kNone));
            for (std::size_t k = 0; k < parts.size(); ++k) {
                part_pred[k][kPg] = pg.part_categories[k];
            }
            std::vector<std::vector<Category>> object_pred(
                r.objects.size(), std::vector<Category>(methods.size(), Category::kNone));
            std::vector<std::vector<std::size_t>> ids(r.objects.size());
            for (std::size_t k = 0; k < parts.size(); ++k) ids[part_object[k]].push_back(k);
            for (std::size_t vi = 0; vi < variant_params.size(); ++vi) {
                const int m = first_variant + kVariantRows * int(vi);
                const PartGraphModel& vmodel = variant_models[vi] ? *variant_models[vi] : model;
                const PartGraphResult vr =
                    RecognizeParts(vmodel, graph, raw, variant_params[vi], part_object);
                for (std::size_t k = 0; k < parts.size(); ++k) {
                    part_pred[k][m] = vr.part_categories[k];
                }
                for (std::size_t ob = 0; ob < r.objects.size(); ++ob) {
                    if (!ids[ob].empty()) {
                        const auto merged = MergePartProbabilities(vr, parts, ids[ob]);
                        const auto& c = r.objects[ob].category;
                        object_pred[ob][m] = object_pred[ob][m + 1] = ArgMaxCategory(merged);
                        object_pred[ob][m + 2] = c.category == Category::kNone
                                                     ? Category::kNone
                                                     : ArgMaxCategory(BlendCategoryProbabilities(
                                                           c.probabilities, merged, blend_weight));
                    }
                }
            }
            // Baseline part features of the frame.
            std::vector<std::array<float, kNumCategories>> vm_part(parts.size()),
                vs_part(parts.size());
            std::vector<bool> vm_keep, vs_keep;
            FeatureMatrix vm_rows, vs_rows;
            if (baselines) {
                vm_rows = MappedParts(model, raw, &vm_keep);
                const FeatureMatrix stats = training::ComputePartStatisticsRows(
                    scan, parts, views[v].linear().transpose() * Eigen::Vector3f::UnitZ());
                vs_rows = DefinedRows(stats, &vs_keep);
                Eigen::Index im = 0, is = 0;
                for (std::size_t k = 0; k < parts.size(); ++k) {
                    vm_part[k] = {};
                    vs_part[k] = {};
                    if (vm_keep[k]) {
                        vm_part[k] = vocab_model.vocabulary.PartProbabilities(
                            {vm_rows.row(im++).data(), kPartMappedSize});
                    }
                    if (vs_keep[k]) {
                        vs_part[k] = vocab_stats.vocabulary.PartProbabilities(
                            {vs_rows.row(is++).data(), kPartStatsSize});
                    }
                    part_pred[k][kVocabModelParts] = ArgMaxCategory(vm_part[k]);
                    part_pred[k][kVocabStatsParts] = ArgMaxCategory(vs_part[k]);
                }
            }
            std::vector<std::array<float, kNumCategories>> object_cluster(r.objects.size());
            std::vector<std::array<float, kNumCategories>> object_three(r.objects.size());
            for (std::size_t ob = 0; ob < r.objects.size(); ++ob) {
                std::vector<Category>& op = object_pred[ob];
                const auto& c = r.objects[ob].category;
                op[kRules] = c.category;
                op[kPg] = op[kPgRules] = op[kPgObject] = Category::kNone;
                if (!ids[ob].empty()) {
                    const auto merged = MergePartProbabilities(pg, parts, ids[ob]);
                    op[kPg] = op[kPgObject] = ArgMaxCategory(merged);
                    // part-graph+rules per object (as perceive blends them).
                    op[kPgRules] = c.category == Category::kNone
                                       ? Category::kNone
                                       : ArgMaxCategory(BlendCategoryProbabilities(
                                             c.probabilities, merged, blend_weight));
                }
                // The three experts as perceive's "part-graph+rules+cluster" combines them.
                op[kFusion3] = op[kPgRules];
                if (op[kFusion3] != Category::kNone) {
                    const auto merged = MergePartProbabilities(pg, parts, ids[ob]);
                    const auto cluster =
                        ClusterExpert(model, scan, r.objects[ob].indices, expert_params);
                    object_cluster[ob] = cluster;
                    object_three[ob] = BlendThreeExperts(c.probabilities, merged, cluster,
                                                         expert_params.expert_weights);
                    op[kFusion3] = ArgMaxCategory(object_three[ob]);
                    if (model.stacker.trained()) {
                        op[kStacked] = ArgMaxCategory(
                            model.stacker.Predict(StackerInputs(c, merged, cluster)));
                    }
                }
                if (!baselines) continue;
                // Part votes merged per object (point-weighted), bags of words, whole cluster.
                std::array<float, kNumCategories> pm{}, ps{};
                FeatureMatrix bm(0, kPartMappedSize), bs(0, kPartStatsSize);
                for (std::size_t k : ids[ob]) {
                    for (std::size_t cc = 0; cc < kNumCategories; ++cc) {
                        pm[cc] += float(parts[k].size()) * vm_part[k][cc];
                        ps[cc] += float(parts[k].size()) * vs_part[k][cc];
                    }
                }
                {
                    Eigen::Index im = 0, is = 0;
                    for (std::size_t k = 0; k < parts.size(); ++k) {
                        const bool mine = part_object[k] == ob;
                        if (vm_keep[k]) {
                            if (mine) {
                                bm.conservativeResize(bm.rows() + 1, Eigen::NoChange);
                                bm.row(bm.rows() - 1) = vm_rows.row(im);
                            }
                            ++im;
                        }
                        if (vs_keep[k]) {
                            if (mine) {
                                bs.conservativeResize(bs.rows() + 1, Eigen::NoChange);
                                bs.row(bs.rows() - 1) = vs_rows.row(is);
                            }
                            ++is;
                        }
                    }
                }
                op[kVocabModelParts] = ArgMaxCategory(pm);
                op[kVocabStatsParts] = ArgMaxCategory(ps);
                op[kVocabModelBow] =
                    bm.rows() ? vocab_model.objects.Predict(vocab_model.vocabulary.BagOfWords(bm))
                              : Category::kNone;
                op[kVocabStatsBow] =
                    bs.rows() ? vocab_stats.objects.Predict(vocab_stats.vocabulary.BagOfWords(bs))
                              : Category::kNone;
                const FeatureVector cd =
                    ComputeClusterDescriptor(scan, r.objects[ob].indices, cluster_params);
                op[kWhole] = cd.cwiseAbs().sum() > 0.0f ? whole.Predict(cd) : Category::kNone;
            }
            // Per-point and per-object counts.
            for (std::size_t ob = 0; ob < r.objects.size(); ++ob) {
                std::array<std::size_t, kNumCategories> hist{};
                for (std::size_t k : ids[ob]) {
                    for (Index i : parts[k]) {
                        const int t = gt_field->data[i];
                        if (t < 1 || t >= static_cast<int>(kNumCategories)) continue;
                        ++hist[t];
                        for (int m = 0; m < int(methods.size()); ++m) {
                            if (skip(m)) continue;
                            const bool per_part =
                                m == kPg || m == kVocabModelParts || m == kVocabStatsParts ||
                                (m >= first_variant && (m - first_variant) % kVariantRows == 0);
                            Category pred = per_part ? part_pred[k][m] : object_pred[ob][m];
                            if (m == kRules) pred = static_cast<Category>(r.point_categories[i]);
                            methods[m].AddPoint(t, pred);
                        }
                    }
                }
                const auto best = std::max_element(hist.begin(), hist.end()) - hist.begin();
                if (hist[best] == 0) continue;
                for (std::size_t t = 1; t < kNumCategories; ++t)
                    for (std::size_t n = 0; n < hist[t]; ++n) ceiling.Add(int(t), int(best));
                if (dump && !ids[ob].empty()) {
                    std::map<std::uint32_t, std::size_t> owners;
                    for (Index i : r.objects[ob].indices) ++owners[scan.labels[i]];
                    std::uint32_t owner = 0;
                    std::size_t most = 0;
                    for (auto [l, n] : owners)
                        if (n > most) most = n, owner = l;
                    std::string src = "?";
                    for (const auto& so : scene.objects)
                        if (so.label == owner) src = so.source;
                    const auto& c = r.objects[ob].category;
                    const auto pgp = MergePartProbabilities(pg, parts, ids[ob]);
                    std::fprintf(dump, "%llu,%d,%zu,\"%s\",%d,%zu", (unsigned long long)seed, s, v,
                                 src.c_str(), int(best), r.objects[ob].indices.size());
                    for (std::size_t q = 1; q < kNumCategories; ++q)
                        std::fprintf(dump, ",%g", double(c.probabilities[q]));
                    for (std::size_t q = 1; q < kNumCategories; ++q)
                        std::fprintf(dump, ",%g", double(pgp[q]));
                    for (std::size_t q = 1; q < kNumCategories; ++q)
                        std::fprintf(dump, ",%g", double(object_cluster[ob][q]));
                    for (std::size_t q = 1; q < kNumCategories; ++q)
                        std::fprintf(dump, ",%g", double(c.scores[q]));
                    std::fprintf(dump, ",%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%d\n",
                                 double(c.extents[0]), double(c.extents[1]), double(c.extents[2]),
                                 double(c.height), double(c.box_score), double(c.axis_area),
                                 double(c.planar_part_ratio), double(c.cylinder_inlier_ratio),
                                 double(c.cylinder_cap_ratio), double(c.cylinder_coverage),
                                 double(c.cylinder_radius), double(c.sphere_inlier_ratio),
                                 double(c.sphere_radius), double(c.footprint_fill),
                                 double(c.side_face_ratio), int(c.upright));
                }
                for (int m = 0; m < int(methods.size()); ++m) {
                    if (skip(m)) continue;
                    methods[m].object.Add(static_cast<int>(best), int(object_pred[ob][m]));
                }
            }
            std::vector<Eigen::Vector3f> world;
            std::vector<std::array<float, kNumCategories>> votes;
            std::vector<int> truth;
            std::vector<Category> pred, pred_o;
            std::vector<std::array<float, kNumCategories>> votes_o, votes_3;
            std::vector<Category> pred_3;
            std::vector<std::array<float, kNumCategories>> object_p(r.objects.size());
            for (std::size_t ob = 0; ob < r.objects.size(); ++ob) {
                if (!ids[ob].empty()) object_p[ob] = MergePartProbabilities(pg, parts, ids[ob]);
            }
            for (std::size_t k = 0; k < parts.size(); ++k) {
                std::array<std::size_t, kNumCategories> hist{};
                for (Index i : parts[k]) {
                    const int t = gt_field->data[i];
                    if (t < 1 || t >= static_cast<int>(kNumCategories)) continue;
                    ++hist[t];
                    world.push_back(views[v] * scan.points[i]);
                    votes.push_back(pg.part_probabilities[k]);
                    truth.push_back(t);
                    pred.push_back(pg.part_categories[k]);
                    votes_o.push_back(object_p[part_object[k]]);
                    pred_o.push_back(ArgMaxCategory(object_p[part_object[k]]));
                    votes_3.push_back(object_three[part_object[k]]);
                    pred_3.push_back(object_pred[part_object[k]][kFusion3]);
                }
                const auto best = std::max_element(hist.begin(), hist.end()) - hist.begin();
                if (hist[best] > 0) part.Add(static_cast<int>(best), int(pg.part_categories[k]));
            }
            grid.Add(world, votes);
            grid_obj.Add(world, votes_o);
            for (auto& vo : votes_o)
                for (float& x : vo) x = std::log(x + 0.01f) - std::log(0.01f);
            grid_prod.Add(world, votes_o);
            grid_three.Add(world, votes_3);
            kept.emplace_back(std::move(world), std::move(truth));
            single.push_back(std::move(pred));
            single_o.push_back(std::move(pred_o));
            single_3.push_back(std::move(pred_3));
        }
        for (std::size_t v = 0; v < kept.size(); ++v) {
            for (std::size_t i = 0; i < kept[v].first.size(); ++i) {
                multi.Add(kept[v].second[i], static_cast<int>(grid.CategoryAt(kept[v].first[i])));
                single_in_multi.Add(kept[v].second[i], static_cast<int>(single[v][i]));
                multi_obj.Add(kept[v].second[i],
                              static_cast<int>(grid_obj.CategoryAt(kept[v].first[i])));
                single_obj.Add(kept[v].second[i], static_cast<int>(single_o[v][i]));
                multi_prod.Add(kept[v].second[i],
                               static_cast<int>(grid_prod.CategoryAt(kept[v].first[i])));
                multi_three.Add(kept[v].second[i],
                                static_cast<int>(grid_three.CategoryAt(kept[v].first[i])));
                single_three.Add(kept[v].second[i], static_cast<int>(single_3[v][i]));
            }
        }
        if (scene_matrices) {
            for (const auto& so : scene.objects) {
                if (so.category == 0) continue;
                std::printf("  object %u: %s (%s), scale %.3f\n", so.label,
                            sim::CategoryNames()[so.category].c_str(), so.source.c_str(), so.scale);
            }
            PrintConfusion("  part-graph in this scene", methods[kPg].scene);
            PrintConfusion("  rules in this scene", methods[kRules].scene);
        }
        for (auto& m : methods) m.EndScene();
        std::printf("scene %d: %zu objects, %zu frames done; part-graph %.3f, rules %.3f\n", s,
                    scene.objects.size(), frames, methods[kPg].scene_accuracy.back(),
                    methods[kRules].scene_accuracy.back());
        std::fflush(stdout);
    }
    if (matrices) {
        for (int m = 0; m < int(methods.size()); ++m) {
            if (skip(m)) continue;
            PrintConfusion(("per point, " + methods[m].name).c_str(), methods[m].point);
            PrintConfusion(("per object, " + methods[m].name).c_str(), methods[m].object);
        }
        PrintConfusion("per part (segment), part-graph hashing", part);
    }
    std::printf("\nsummary over %d scenes (%zu points, %zu perceived objects with a category):\n",
                scenes, methods[kPg].point.Total(), methods[kPg].object.Total());
    std::printf("%-56s %9s %9s %19s\n", "method", "per point", "per object", "per scene mean+-sd");
    for (int m = 0; m < int(methods.size()); ++m) {
        if (skip(m)) continue;
        const auto [mean, sd] = MeanStd(methods[m].scene_accuracy);
        std::printf("%-56s %9.3f %9.3f %11.3f +- %.3f\n", methods[m].name.c_str(),
                    methods[m].point.Accuracy(), methods[m].object.Accuracy(), mean, sd);
    }
    std::printf("per part (segment), part-graph hashing: %.3f\n", part.Accuracy());
    std::printf(
        "ceiling of per-object labels (each perceived object named by its points' majority "
        "truth): %.3f per point\n",
        ceiling.Accuracy());
    std::printf("multi-view (6 views, 5 mm voxel votes): %.3f per point vs %.3f single views\n",
                multi.Accuracy(), single_in_multi.Accuracy());
    std::printf(
        "multi-view, object votes (each point votes with its object's distribution, as perceive "
        "--manifest fuses): %.3f per point vs %.3f single views\n",
        multi_obj.Accuracy(), single_obj.Accuracy());
    std::printf("multi-view, object votes, product rule: %.3f per point vs %.3f single views\n",
                multi_prod.Accuracy(), single_obj.Accuracy());
    std::printf(
        "multi-view, object votes of part-graph+rules+cluster: %.3f per point vs %.3f single "
        "views\n",
        multi_three.Accuracy(), single_three.Accuracy());
    std::printf(
        "categorising all parts of a 640x480 frame: %.1f ms mean over %zu frames "
        "(%.1f parts per frame; graph, GRSD- and votes; 1 thread)\n",
        recog_ms / double(std::max<std::size_t>(frames, 1)), frames,
        double(parts_total) / double(std::max<std::size_t>(frames, 1)));
    if (dump) std::fclose(dump);
    return 0;
}
