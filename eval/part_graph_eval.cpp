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
//                        [--scene-matrices 0|1] [--distance-weighted 0|1] [--size-exponent E]
//                        [--grsd-weight W] [--elevation-weight W] [--rsd-weight W]
//                        [--extent-weights A,B,C] [--upright-extents 0|1] [--variants
//                        "k=10;ew=2,rw=1;..."] [--stacker-scenes N] [--stacker-views N]
//                        [--dump FILE.csv] [--even-test 0|1] [--procedural-test 0|1]
//                        [--expert-weights R,P,C]
//
// `--help` lists the options with their defaults; a bad option or value prints one line and
// exits with status 2. --meshes defaults to $MULTICUE_DATA/meshes/tabletop, else to the
// meshes/tabletop of the shared data folder the build was configured with
// (MULTICUE_SHARED_DATA_DIR); a folder without labels.csv means procedural objects only.
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

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "driver_options.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/features/part_stats.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/ml/evaluation.hpp"
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

using Distribution = std::array<float, kNumCategories>;

// ---------------------------------------------------------------------------------------------
// Counting. Truth is never kNone; predictions of kNone count as errors.

ml::ConfusionCounter CategoryCounter() {
    std::vector<std::string> names;
    for (const auto name : kCategoryNames) names.emplace_back(name);
    return ml::ConfusionCounter(std::move(names));
}

constexpr int kUnscored = static_cast<int>(Category::kNone);  // not a true category

double Accuracy(const ml::ConfusionCounter& c) { return c.ToMatrix().AccuracyExcluding(kUnscored); }

std::size_t Scored(const ml::ConfusionCounter& c) { return c.ToMatrix().TotalExcluding(kUnscored); }

// Balanced accuracy: the mean over the true categories present of the share of their points (or
// objects) named right; and the worst of those categories with its share.
struct Balanced {
    double mean = 0.0;
    std::string worst;
    double worst_share = 1.0;
};

Balanced BalancedAccuracy(const ml::ConfusionCounter& c) {
    const ml::ConfusionMatrix m = c.ToMatrix();
    Balanced b;
    int present = 0;
    for (Eigen::Index t = 0; t < m.counts.rows(); ++t) {
        if (t == kUnscored) continue;
        const double total = static_cast<double>(m.counts.row(t).sum());
        if (total <= 0.0) continue;
        const double share = static_cast<double>(m.counts(t, t)) / total;
        b.mean += share;
        ++present;
        if (share < b.worst_share) {
            b.worst_share = share;
            b.worst = m.class_names[static_cast<std::size_t>(t)];
        }
    }
    if (present > 0) b.mean /= present;
    return b;
}

void PrintConfusion(const std::string& title, const ml::ConfusionCounter& c) {
    const ml::ConfusionMatrix m = c.ToMatrix();
    std::printf("%s (rows truth, columns predicted; accuracy %.3f over %zu)\n", title.c_str(),
                m.AccuracyExcluding(kUnscored), m.TotalExcluding(kUnscored));
    std::printf("%10s", "");
    for (const auto& name : m.class_names) std::printf("%9s", name.c_str());
    std::printf("\n");
    for (Eigen::Index t = 1; t < m.counts.rows(); ++t) {
        std::printf("%10s", m.class_names[static_cast<std::size_t>(t)].c_str());
        for (Eigen::Index p = 0; p < m.counts.cols(); ++p) {
            std::printf("%9zu", static_cast<std::size_t>(m.counts(t, p)));
        }
        std::printf("\n");
    }
}

// One categoriser's counts: per point, per perceived object, per point in each scene.
struct Method {
    explicit Method(std::string method_name) : name(std::move(method_name)) {}
    std::string name;
    ml::ConfusionCounter point = CategoryCounter(), object = CategoryCounter(),
                         scene = CategoryCounter();
    std::vector<double> scene_accuracy;
    void EndScene() {
        if (Scored(scene) > 0) scene_accuracy.push_back(Accuracy(scene));
        scene.Clear();
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

// ---------------------------------------------------------------------------------------------
// Options.

std::string DefaultMeshes() {
    const char* env = std::getenv("MULTICUE_DATA");
    const std::string data = env != nullptr && *env != '\0' ? env : MULTICUE_SHARED_DATA_DIR;
    return data + "/meshes/tabletop";
}

PartVocabularyParams DefaultVocabulary() {
    PartVocabularyParams vp;
    vp.words = 200;
    vp.num_threads = 0;
    return vp;
}

struct Options {
    std::string meshes = DefaultMeshes();
    int scenes = 4;
    int max_meshes = 0;  // 0: every even-indexed mesh
    std::uint64_t seed = 1;
    PartDescriptorParams descriptor = PartGraphModel{}.descriptor_params;
    // Recognition and blend as perceive runs them (parts grouped by object, its category priors).
    PartGraphRecognitionParams recognition = CategorizationParams{}.part_graph;
    float blend_weight = CategorizationParams{}.part_graph_weight;
    int baselines = 1;
    int matrices = 1;
    bool scene_matrices = false;
    PartVocabularyParams vocabulary = DefaultVocabulary();
    std::string object_spec = "knn:k=5";
    std::string variants;
    int stacker_scenes = 0;  // held-out scenes training the stacker
    int stacker_views = 6;
    bool even_test = false;        // test scenes of the training meshes (seen instances)
    bool procedural_test = false;  // test scenes of procedural objects even with a library
    std::string dump_path;  // one CSV row per perceived object: truth, experts, rule evidence
    Eigen::Vector3f expert_weights = CategorizationParams{}.expert_weights;
    ClusterDescriptorParams cluster_params;
    int table_scenes = -1;  // -1: as multicue train
    int table_views = 4;
    int objects = 8;
    int train_meshes = 1;
};

// A further part-graph setting of --variants; own_model: its descriptor differs from the main
// model's, so it trains a model of its own.
struct Variant {
    std::string spec;
    PartGraphRecognitionParams recognition;
    PartDescriptorParams descriptor;
    bool own_model = false;
};

// One "key=value,key=value" setting of --variants on top of the main recognition and descriptor.
Variant ParseVariant(const std::string& spec, const PartGraphRecognitionParams& recognition,
                     const PartDescriptorParams& descriptor) {
    Variant v{spec, recognition, descriptor, false};
    PartGraphRecognitionParams& vr = v.recognition;
    PartDescriptorParams& vd = v.descriptor;
    std::size_t b = 0;
    while (b < spec.size()) {
        std::size_t e = spec.find(',', b);
        if (e == std::string::npos) e = spec.size();
        const std::string kv = spec.substr(b, e - b);
        b = e + 1;
        const auto eq = kv.find('=');
        if (eq == std::string::npos) throw CLI::ValidationError("--variants", "bad variant " + kv);
        const std::string key = kv.substr(0, eq);
        const double val = std::strtod(kv.c_str() + eq + 1, nullptr);
        if (key == "k") {
            vr.k = std::size_t(val);
        } else if (key == "dw") {
            vr.distance_weighted = val != 0.0;
        } else if (key == "off") {
            vr.distance_offset = float(val);
        } else if (key == "se") {
            vr.size_exponent = float(val);
        } else if (key == "mp") {
            vr.max_parts = std::size_t(val);
        } else if (key == "cw") {
            vr.confidence_weighted = val != 0.0;
        } else if (key == "bal") {
            vr.balanced = val != 0.0;
        } else if (key == "wo") {
            vr.within_groups = val != 0.0;
        } else if (key == "ow") {
            vr.group_weight = float(val);
        } else if (key.size() == 2 && key[0] == 'p' &&
                   std::string_view("sbfcpo").find(key[1]) != std::string_view::npos) {
            // prior: ps, pb, pf, pc, pp, po
            vr.category_priors[std::string_view("sbfcpo").find(key[1]) + 1] = float(val);
        } else if (key == "ue") {
            v.own_model = true;
            vd.upright_extents = val != 0.0;
        } else if (key == "gw" || key == "ew" || key == "rw" || key == "sw" || key == "e1" ||
                   key == "e2" || key == "e3") {
            v.own_model = true;
            float& w = key == "gw"   ? vd.grsd_weight
                       : key == "ew" ? vd.elevation_weight
                       : key == "rw" ? vd.rsd_weight
                       : key == "sw" ? vd.size_weight
                       : key == "e1" ? vd.extent_weights[0]
                       : key == "e2" ? vd.extent_weights[1]
                                     : vd.extent_weights[2];
            w = float(val);
        } else {
            throw CLI::ValidationError("--variants", "bad variant key " + key);
        }
    }
    return v;
}

// The settings of --variants ("k=10,dw=1;se=0.5"), empty ones skipped.
std::vector<Variant> ParseVariants(const Options& o) {
    std::vector<Variant> out;
    std::size_t begin = 0;
    while (begin < o.variants.size()) {
        std::size_t end = o.variants.find(';', begin);
        if (end == std::string::npos) end = o.variants.size();
        const std::string spec = o.variants.substr(begin, end - begin);
        begin = end + 1;
        if (!spec.empty()) out.push_back(ParseVariant(spec, o.recognition, o.descriptor));
    }
    return out;
}

// "A,B,C" into three floats; false unless the whole text is three numbers.
bool ParseTriple(const std::string& text, float* out) {
    int used = 0;
    return std::sscanf(text.c_str(), "%f,%f,%f%n", &out[0], &out[1], &out[2], &used) == 3 &&
           used == static_cast<int>(text.size());
}

std::string TripleText(const float* v) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%g,%g,%g", double(v[0]), double(v[1]), double(v[2]));
    return buf;
}

// An option taking 0 or 1 (any non-zero integer counts as 1) stored in a bool.
void AddSwitch(CLI::App& app, const std::string& name, bool& target, const std::string& help) {
    app.add_option_function<int>(
           name, [&target](int v) { target = v != 0; }, help)
        ->type_name("0|1")
        ->default_str(target ? "1" : "0");
}

void AddTestOptions(CLI::App& app, Options& o) {
    app.add_option("--meshes", o.meshes,
                   "mesh library folder with labels.csv (without it: procedural objects only)")
        ->type_name("DIR")
        ->capture_default_str();
    app.add_option("--scenes", o.scenes, "test scenes")->capture_default_str();
    app.add_option("--seed", o.seed, "seed of training, test scenes and scans")
        ->capture_default_str();
    AddSwitch(app, "--even-test", o.even_test,
              "test on scenes of the training (even-indexed) meshes");
    AddSwitch(app, "--procedural-test", o.procedural_test,
              "test on scenes of procedural objects even with a library");
    app.add_option("--blend-weight", o.blend_weight,
                   "part-graph weight in part-graph+rules (perceive's default)")
        ->capture_default_str();
    app.add_option_function<std::string>(
           "--expert-weights",
           [&o](const std::string& s) {
               if (!ParseTriple(s, o.expert_weights.data())) {
                   throw CLI::ValidationError("--expert-weights", "needs R,P,C, got '" + s + "'");
               }
           },
           "weights of rules, part-graph and cluster expert in part-graph+rules+cluster")
        ->type_name("R,P,C")
        ->default_str(TripleText(o.expert_weights.data()));
    app.add_option("--variants", o.variants,
                   "further part-graph settings, ';' between settings, ',' between key=value "
                   "(keys below)")
        ->type_name("SPEC");
    app.add_option("--matrices", o.matrices, "print the confusion matrices (0|1)")
        ->capture_default_str();
    AddSwitch(app, "--scene-matrices", o.scene_matrices,
              "print each scene's objects and confusion matrices");
    app.add_option("--dump", o.dump_path, "write one CSV row per perceived object")
        ->type_name("FILE.csv");
}

void AddTrainingOptions(CLI::App& app, Options& o) {
    app.add_option("--max-meshes", o.max_meshes, "training meshes at most (0: every even one)")
        ->capture_default_str();
    app.add_option("--objects", o.objects, "procedural training objects per category")
        ->capture_default_str();
    app.add_option("--train-meshes", o.train_meshes,
                   "scan the training meshes on the turntable (0|1)")
        ->capture_default_str();
    app.add_option("--table-scenes", o.table_scenes,
                   "training table scenes (-1: as multicue train, 40 or 80 with library meshes)")
        ->capture_default_str();
    app.add_option("--table-views", o.table_views, "views per training table scene")
        ->capture_default_str();
    app.add_option("--stacker-scenes", o.stacker_scenes,
                   "held-out scenes training the stacker (0: none)")
        ->capture_default_str();
    app.add_option("--stacker-views", o.stacker_views, "views per stacker scene")
        ->capture_default_str();
    PartDescriptorParams& d = o.descriptor;
    app.add_option("--size-weight", d.size_weight, "weight of the extents")->capture_default_str();
    app.add_option("--grsd-weight", d.grsd_weight, "weight of the GRSD- block")
        ->capture_default_str();
    app.add_option("--elevation-weight", d.elevation_weight, "weight of the elevation block")
        ->capture_default_str();
    app.add_option("--rsd-weight", d.rsd_weight, "weight of the curvature block")
        ->capture_default_str();
    app.add_option_function<std::string>(
           "--extent-weights",
           [&d](const std::string& s) {
               if (!ParseTriple(s, d.extent_weights.data())) {
                   throw CLI::ValidationError("--extent-weights", "needs A,B,C, got '" + s + "'");
               }
           },
           "factors of the largest, middle and smallest extent")
        ->type_name("A,B,C")
        ->default_str(TripleText(d.extent_weights.data()));
    AddSwitch(app, "--upright-extents", d.upright_extents, "extents against up, not principal");
}

void AddRecognitionOptions(CLI::App& app, Options& o) {
    PartGraphRecognitionParams& r = o.recognition;
    app.add_option("--k", r.k, "neighbours voting per subgraph")->capture_default_str();
    app.add_option("--max-parts", r.max_parts, "largest subgraph")->capture_default_str();
    AddSwitch(app, "--balanced", r.balanced, "balanced votes");
    AddSwitch(app, "--distance-weighted", r.distance_weighted, "votes weighted by distance");
    app.add_option("--size-exponent", r.size_exponent, "vote weight 1 / size^E")
        ->capture_default_str();
    app.add_option("--baselines", o.baselines, "train and count the baselines (0|1)")
        ->capture_default_str();
    app.add_option("--words", o.vocabulary.words, "words of the vocabularies of parts")
        ->capture_default_str();
    app.add_option("--activations", o.vocabulary.activations, "words a part activates")
        ->capture_default_str();
    app.add_option("--object-classifier", o.object_spec,
                   "classifier of bags of words and whole clusters")
        ->type_name("SPEC")
        ->capture_default_str();
    app.add_option("--cluster-size-weight", o.cluster_params.size_weight,
                   "weight of the extents in the whole-cluster descriptor")
        ->capture_default_str();
}

// Fills `o` and `variants` from the command line; an exit status when the program should stop
// (0 after --help, 2 for a bad option or value, reported in one line).
std::optional<int> ParseOptions(int argc, char** argv, Options& o, std::vector<Variant>& variants) {
    CLI::App app{"part_graph_eval: part-graph hashing and its baselines in simulated clutter"};
    app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    app.footer(
        "--meshes defaults to $MULTICUE_DATA/meshes/tabletop, else to that folder of the shared "
        "data folder the build was configured with.\n"
        "--variants keys: recognition k, dw, off, se, mp, cw, bal, wo, ow and the category priors "
        "ps, pb, pf, pc, pp, po; descriptor (a model of its own) gw, ew, rw, sw, e1, e2, e3, ue. "
        "Example: --variants \"k=10;ew=2,rw=1\".");
    AddTestOptions(app, o);
    AddTrainingOptions(app, o);
    AddRecognitionOptions(app, o);
    return eval::ParseDriverOptions(app, "part_graph_eval", [&] {
        app.parse(argc, argv);
        variants = ParseVariants(o);
    });
}

// ---------------------------------------------------------------------------------------------
// Training.

struct Training {
    PartGraphModel model;
    training::PartGraphTrainingOptions options;
    std::vector<training::TrainingObject> objects;
    bool library = false;
};

// The model as multicue train trains it (even-indexed library meshes); prints its line.
void TrainModel(const Options& o, bool keep_objects, Training& t) {
    t.library = std::filesystem::exists(std::filesystem::path(o.meshes) / "labels.csv");
    const int table_scenes = o.table_scenes >= 0 ? o.table_scenes
                             : t.library && o.train_meshes
                                 ? training::kLibraryTableScenes
                                 : training::PartGraphTrainingOptions{}.table_scenes;
    training::PartGraphTrainingOptions& to = t.options;
    to.seed = o.seed;
    to.objects_per_category = o.objects;
    to.table_scenes = table_scenes;
    to.table_views = o.table_views;
    to.stacker_scenes = o.stacker_scenes;
    to.stacker_views = o.stacker_views;
    if (t.library) {
        to.meshes = o.meshes;
        to.mesh_modulo = 2;
        to.mesh_remainder = 0;
        to.max_meshes = o.max_meshes;
        to.mesh_turntable = o.train_meshes != 0;
    }
    if (keep_objects) to.objects_out = &t.objects;
    if (o.baselines) {
        to.cluster_params = o.cluster_params;
        to.part_statistics = true;
    }
    t.model.descriptor_params = o.descriptor;
    const auto t0 = std::chrono::steady_clock::now();
    training::TrainPartGraphModel(t.model, to);
    const double train_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const PartDescriptorParams& d = t.model.descriptor_params;
    std::fflush(stdout);
    std::printf(
        "training: %zu subgraphs, %zu buckets, %.1f s (%d procedural objects per category, %s, "
        "%d table scenes x %d views; size weight %g, extents x %g %g %g, GRSD- %g, elevation %g, "
        "curvature %g, %s extents, %s votes)\n",
        t.model.num_rows(), t.model.num_buckets(), train_s, o.objects,
        t.library && o.train_meshes ? "even library meshes" : "no library meshes", table_scenes,
        o.table_views, double(d.size_weight), double(d.extent_weights[0]),
        double(d.extent_weights[1]), double(d.extent_weights[2]), double(d.grsd_weight),
        double(d.elevation_weight), double(d.rsd_weight),
        d.upright_extents ? "upright" : "principal", o.recognition.balanced ? "balanced" : "plain");
    if (t.model.stacker.trained()) {
        std::printf("stacker: %zu perceived objects of %d held-out scenes x %d views\n",
                    t.model.stacker.train_rows(), o.stacker_scenes, o.stacker_views);
    }
}

// Models of the variants with a descriptor of their own, from the same training rows, graphs and
// sampling seeds (nullptr: the variant uses the main model).
std::vector<std::shared_ptr<const PartGraphModel>> TrainVariantModels(
    const std::vector<Variant>& variants, const Training& t) {
    std::vector<std::shared_ptr<const PartGraphModel>> out;
    for (const Variant& v : variants) {
        if (!v.own_model) {
            out.push_back(nullptr);
            continue;
        }
        auto vm = std::make_shared<PartGraphModel>();
        vm->graph_params = t.model.graph_params;
        vm->descriptor_params = v.descriptor;
        for (const auto& object : t.objects) {
            PartGraphTrainParams tp = t.options.train;
            tp.seed = object.train_seed;
            vm->AddObject(object.part_descriptors, object.graph, object.category, tp);
        }
        vm->Build();
        out.push_back(std::move(vm));
    }
    return out;
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

// The baselines trained on the model's training objects.
struct Baselines {
    VocabularyBaseline vocab_model, vocab_stats;
    ObjectClassifier whole;
};

// Trains the baselines and prints their line.
void TrainBaselines(const Options& o, const Training& t, Baselines& b) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<FeatureMatrix> mapped, stats;
    std::vector<Category> labels;
    std::vector<FeatureVector> clusters;
    for (const auto& object : t.objects) {
        mapped.push_back(MappedParts(t.model, object.part_descriptors));
        stats.push_back(DefinedRows(object.part_statistics));
        labels.push_back(object.category);
        clusters.push_back(object.cluster);
    }
    b.vocab_model = TrainVocabulary(mapped, labels, o.vocabulary, o.object_spec);
    PartVocabularyParams sp = o.vocabulary;
    sp.normalize = true;
    b.vocab_stats = TrainVocabulary(stats, labels, sp, o.object_spec);
    b.whole.Fit(clusters, labels, o.object_spec);
    std::printf(
        "baselines: %zu training objects, %zu / %zu parts, %zu words, %zu activations, object "
        "classifier %s, %.1f s\n",
        t.objects.size(), b.vocab_model.train_parts, b.vocab_stats.train_parts,
        b.vocab_model.vocabulary.num_words(), o.vocabulary.activations, o.object_spec.c_str(),
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

// ---------------------------------------------------------------------------------------------
// The categorisers counted (rows of the report).

enum MethodId {
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

// Three rows per variant: part labels, each object's merged label, that blended with the rules
// (--blend-weight).
constexpr int kVariantRows = 3;
constexpr int kFirstVariant = kNumMethods;

// Which rows are counted: the baselines only with --baselines, "stacked" only with a stacker.
struct MethodSet {
    int num_methods = kNumMethods;  // rows before the variants that are counted
    bool stacked = false;
    bool Skip(int m) const {
        return (m >= num_methods && m < kFirstVariant) || (m == kStacked && !stacked);
    }
};

std::vector<Method> MakeMethods(const Options& o, const std::vector<Variant>& variants) {
    char blend_name[64];
    std::snprintf(blend_name, sizeof blend_name, "part-graph+rules (weight %.2f)",
                  double(o.blend_weight));
    std::vector<Method> methods;
    methods.emplace_back("part-graph hashing");                         // kPg
    methods.emplace_back(blend_name);                                   // kPgRules
    methods.emplace_back("rule-based categoriser (perceive default)");  // kRules
    methods.emplace_back("part-graph hashing, object categories (as perceive labels)");
    methods.emplace_back("part-graph+rules+cluster (rules x part-graph x model's cluster k-NN)");
    methods.emplace_back("stacked (level-1 classifier over the three experts)");  // kStacked
    methods.emplace_back("vocabulary of parts, model descriptor, part votes");
    methods.emplace_back("vocabulary of parts, model descriptor, bag of words");
    methods.emplace_back("vocabulary of parts, 24 part statistics, part votes");
    methods.emplace_back("vocabulary of parts, 24 part statistics, bag of words");
    methods.emplace_back("whole cluster, GRSD- + VFH");  // kWhole
    for (const Variant& v : variants) {
        methods.emplace_back("part-graph " + v.spec);
        methods.emplace_back("part-graph " + v.spec + ", object labels");
        methods.emplace_back("part-graph " + v.spec + ", +rules");
    }
    return methods;
}

// ---------------------------------------------------------------------------------------------
// Evaluation on the test scenes.

// Everything the test frames are categorised with.
struct Evaluator {
    const Options& options;
    const PartGraphModel& model;
    const Baselines& baselines;
    const std::vector<Variant>& variants;
    const std::vector<std::shared_ptr<const PartGraphModel>>& variant_models;
    MethodSet set;
    PerceiveParams perceive;
    CategorizationParams experts;  // the experts as perceive runs them
    std::FILE* dump = nullptr;
};

// Every count of the run.
struct Tally {
    std::vector<Method> methods;
    ml::ConfusionCounter part = CategoryCounter(), multi = CategoryCounter(),
                         single_in_multi = CategoryCounter();
    // every perceived object named by the majority truth of its points
    ml::ConfusionCounter ceiling = CategoryCounter();
    // votes with each object's distribution (as perceive fuses)
    ml::ConfusionCounter multi_obj = CategoryCounter(), single_obj = CategoryCounter();
    // the same votes as log(p + 0.01) - log(0.01): product rule
    ml::ConfusionCounter multi_prod = CategoryCounter();
    // object votes of part-graph+rules+cluster
    ml::ConfusionCounter multi_three = CategoryCounter(), single_three = CategoryCounter();
    double recog_ms = 0.0;
    std::size_t frames = 0, parts_total = 0;
};

// One perceived test frame with its parts recognised by the main model.
struct Frame {
    PointCloud scan;
    const ExtraField* truth = nullptr;  // per-point category (u8)
    PerceiveResult perceived;
    std::vector<Indices> parts;
    std::vector<std::uint32_t> part_object;     // also the recognition's part groups
    std::vector<std::vector<std::size_t>> ids;  // parts of each perceived object
    PartGraph graph;
    FeatureMatrix raw;  // part descriptors
    PartGraphResult pg;
};

// Every method's labels of a frame: per part (object-level methods: the object's) and per object.
struct Predictions {
    std::vector<std::vector<Category>> part, object;
    std::vector<Distribution> merged;   // part-graph probabilities merged per object
    std::vector<Distribution> cluster;  // the whole-object expert (with part-graph+rules+cluster)
    std::vector<Distribution> three;    // part-graph+rules+cluster
};

// Scans one view, perceives it as perceive does and recognises its parts (timed).
void PerceiveFrame(const Evaluator& ev, const sim::RayCaster& caster, const Eigen::Isometry3f& view,
                   std::uint64_t scan_seed, Tally& tally, Frame& f) {
    f.scan = sim::ScanKinect(caster, view, {}, scan_seed);
    f.truth = f.scan.FindExtraField("category");
    if (!f.truth) throw DataError("scan without category field");
    {  // normals as perceive computes them; perceive keeps them
        OrganizedNormalParams np = ev.perceive.normals.organized;
        SetNormals(f.scan, EstimateNormalsOrganized(f.scan, np));
    }
    f.perceived = Perceive(f.scan, ev.perceive);
    for (std::size_t ob = 0; ob < f.perceived.objects.size(); ++ob)
        for (const auto& p : f.perceived.objects[ob].parts) {
            f.parts.push_back(p);
            f.part_object.push_back(static_cast<std::uint32_t>(ob));
        }
    const auto a = std::chrono::steady_clock::now();
    f.graph = BuildPartGraph(f.scan, f.parts, ev.model.graph_params);
    // Up as perceive knows it: the support plane's normal (camera -y without one).
    const Eigen::Vector3f up = f.perceived.support.found
                                   ? Eigen::Vector3f(f.perceived.support.plane.head<3>())
                                   : Eigen::Vector3f::Zero();
    f.raw = ComputePartDescriptors(f.scan, f.parts, ev.model.descriptor_params, up);
    f.pg = RecognizeParts(ev.model, f.graph, f.raw, ev.options.recognition, f.part_object);
    tally.recog_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count();
    ++tally.frames;
    tally.parts_total += f.parts.size();
    f.ids.assign(f.perceived.objects.size(), {});
    for (std::size_t k = 0; k < f.parts.size(); ++k) f.ids[f.part_object[k]].push_back(k);
}

// The variants' labels: per part, per object, per object blended with the rules.
void PredictVariants(const Evaluator& ev, const Frame& f, Predictions& p) {
    for (std::size_t vi = 0; vi < ev.variants.size(); ++vi) {
        const int m = kFirstVariant + kVariantRows * int(vi);
        const PartGraphModel& vmodel = ev.variant_models[vi] ? *ev.variant_models[vi] : ev.model;
        const PartGraphResult vr =
            RecognizeParts(vmodel, f.graph, f.raw, ev.variants[vi].recognition, f.part_object);
        for (std::size_t k = 0; k < f.parts.size(); ++k) p.part[k][m] = vr.part_categories[k];
        for (std::size_t ob = 0; ob < f.perceived.objects.size(); ++ob) {
            if (f.ids[ob].empty()) continue;
            const auto merged = MergePartProbabilities(vr, f.parts, f.ids[ob]);
            const auto& c = f.perceived.objects[ob].category;
            p.object[ob][m] = p.object[ob][m + 1] = ArgMaxCategory(merged);
            p.object[ob][m + 2] = c.category == Category::kNone
                                      ? Category::kNone
                                      : ArgMaxCategory(BlendCategoryProbabilities(
                                            c.probabilities, merged, ev.options.blend_weight));
        }
    }
}

// The baselines' part features of a frame and the vocabularies' part votes.
struct BaselineParts {
    std::vector<Distribution> vm_part, vs_part;  // model descriptor, part statistics
    std::vector<bool> vm_keep, vs_keep;          // parts with a row
    FeatureMatrix vm_rows, vs_rows;
};

void PredictBaselineParts(const Evaluator& ev, const Frame& f, const Eigen::Isometry3f& view,
                          BaselineParts& b, Predictions& p) {
    const Baselines& bl = ev.baselines;
    b.vm_part.assign(f.parts.size(), {});
    b.vs_part.assign(f.parts.size(), {});
    b.vm_rows = MappedParts(ev.model, f.raw, &b.vm_keep);
    const FeatureMatrix stats = training::ComputePartStatisticsRows(
        f.scan, f.parts, view.linear().transpose() * Eigen::Vector3f::UnitZ());
    b.vs_rows = DefinedRows(stats, &b.vs_keep);
    Eigen::Index im = 0, is = 0;
    for (std::size_t k = 0; k < f.parts.size(); ++k) {
        if (b.vm_keep[k]) {
            b.vm_part[k] = bl.vocab_model.vocabulary.PartProbabilities(
                {b.vm_rows.row(im++).data(), kPartMappedSize});
        }
        if (b.vs_keep[k]) {
            b.vs_part[k] = bl.vocab_stats.vocabulary.PartProbabilities(
                {b.vs_rows.row(is++).data(), kPartStatsSize});
        }
        p.part[k][kVocabModelParts] = ArgMaxCategory(b.vm_part[k]);
        p.part[k][kVocabStatsParts] = ArgMaxCategory(b.vs_part[k]);
    }
}

// The baselines' labels of perceived object `ob`: part votes merged per object (point-weighted),
// bags of words, whole cluster.
void PredictObjectBaselines(const Evaluator& ev, const Frame& f, const BaselineParts& b,
                            std::size_t ob, std::vector<Category>& op) {
    const Baselines& bl = ev.baselines;
    Distribution pm{}, ps{};
    FeatureMatrix bm(0, kPartMappedSize), bs(0, kPartStatsSize);
    for (std::size_t k : f.ids[ob]) {
        for (std::size_t cc = 0; cc < kNumCategories; ++cc) {
            pm[cc] += float(f.parts[k].size()) * b.vm_part[k][cc];
            ps[cc] += float(f.parts[k].size()) * b.vs_part[k][cc];
        }
    }
    Eigen::Index im = 0, is = 0;
    for (std::size_t k = 0; k < f.parts.size(); ++k) {
        const bool mine = f.part_object[k] == ob;
        if (b.vm_keep[k]) {
            if (mine) {
                bm.conservativeResize(bm.rows() + 1, Eigen::NoChange);
                bm.row(bm.rows() - 1) = b.vm_rows.row(im);
            }
            ++im;
        }
        if (b.vs_keep[k]) {
            if (mine) {
                bs.conservativeResize(bs.rows() + 1, Eigen::NoChange);
                bs.row(bs.rows() - 1) = b.vs_rows.row(is);
            }
            ++is;
        }
    }
    op[kVocabModelParts] = ArgMaxCategory(pm);
    op[kVocabStatsParts] = ArgMaxCategory(ps);
    op[kVocabModelBow] =
        bm.rows() ? bl.vocab_model.objects.Predict(bl.vocab_model.vocabulary.BagOfWords(bm))
                  : Category::kNone;
    op[kVocabStatsBow] =
        bs.rows() ? bl.vocab_stats.objects.Predict(bl.vocab_stats.vocabulary.BagOfWords(bs))
                  : Category::kNone;
    const FeatureVector cd = ComputeClusterDescriptor(f.scan, f.perceived.objects[ob].indices,
                                                      ev.options.cluster_params);
    op[kWhole] = cd.cwiseAbs().sum() > 0.0f ? bl.whole.Predict(cd) : Category::kNone;
}

// The object-level labels of the main rows (and of the baselines) for every perceived object.
void PredictObjects(const Evaluator& ev, const Frame& f, const BaselineParts& b, Predictions& p) {
    const std::size_t n = f.perceived.objects.size();
    p.merged.assign(n, {});
    p.cluster.assign(n, {});
    p.three.assign(n, {});
    for (std::size_t ob = 0; ob < n; ++ob) {
        std::vector<Category>& op = p.object[ob];
        const auto& c = f.perceived.objects[ob].category;
        op[kRules] = c.category;
        op[kPg] = op[kPgRules] = op[kPgObject] = Category::kNone;
        if (!f.ids[ob].empty()) {
            p.merged[ob] = MergePartProbabilities(f.pg, f.parts, f.ids[ob]);
            op[kPg] = op[kPgObject] = ArgMaxCategory(p.merged[ob]);
            // part-graph+rules per object (as perceive blends them).
            op[kPgRules] = c.category == Category::kNone
                               ? Category::kNone
                               : ArgMaxCategory(BlendCategoryProbabilities(
                                     c.probabilities, p.merged[ob], ev.options.blend_weight));
        }
        // The three experts as perceive's "part-graph+rules+cluster" combines them.
        op[kFusion3] = op[kPgRules];
        if (op[kFusion3] != Category::kNone) {
            p.cluster[ob] =
                ClusterExpert(ev.model, f.scan, f.perceived.objects[ob].indices, ev.experts);
            p.three[ob] = BlendThreeExperts(c.probabilities, p.merged[ob], p.cluster[ob],
                                            ev.experts.expert_weights);
            op[kFusion3] = ArgMaxCategory(p.three[ob]);
            if (ev.model.stacker.trained()) {
                op[kStacked] = ArgMaxCategory(
                    ev.model.stacker.Predict(StackerInputs(c, p.merged[ob], p.cluster[ob])));
            }
        }
        if (ev.options.baselines) PredictObjectBaselines(ev, f, b, ob, op);
    }
}

// Where a test frame comes from (for --dump).
struct FrameId {
    int scene = 0;
    std::size_t view = 0;
    const sim::Scene* sim_scene = nullptr;
};

// One --dump row: perceived object `ob` with majority truth `best`.
void WriteDumpRow(const Evaluator& ev, const FrameId& id, const Frame& f, const Predictions& p,
                  std::size_t ob, int best) {
    std::FILE* dump = ev.dump;
    std::map<std::uint32_t, std::size_t> owners;
    for (Index i : f.perceived.objects[ob].indices) ++owners[f.scan.labels[i]];
    std::uint32_t owner = 0;
    std::size_t most = 0;
    for (auto [l, n] : owners)
        if (n > most) most = n, owner = l;
    std::string src = "?";
    for (const auto& so : id.sim_scene->objects)
        if (so.label == owner) src = so.source;
    const auto& c = f.perceived.objects[ob].category;
    const auto& pgp = p.merged[ob];
    std::fprintf(dump, "%llu,%d,%zu,\"%s\",%d,%zu", (unsigned long long)ev.options.seed, id.scene,
                 id.view, src.c_str(), best, f.perceived.objects[ob].indices.size());
    for (std::size_t q = 1; q < kNumCategories; ++q)
        std::fprintf(dump, ",%g", double(c.probabilities[q]));
    for (std::size_t q = 1; q < kNumCategories; ++q) std::fprintf(dump, ",%g", double(pgp[q]));
    for (std::size_t q = 1; q < kNumCategories; ++q)
        std::fprintf(dump, ",%g", double(p.cluster[ob][q]));
    for (std::size_t q = 1; q < kNumCategories; ++q) std::fprintf(dump, ",%g", double(c.scores[q]));
    std::fprintf(dump, ",%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%g,%d,%g\n",
                 double(c.extents[0]), double(c.extents[1]), double(c.extents[2]), double(c.height),
                 double(c.box_score), double(c.axis_area), double(c.planar_part_ratio),
                 double(c.cylinder_inlier_ratio), double(c.cylinder_cap_ratio),
                 double(c.cylinder_coverage), double(c.cylinder_radius),
                 double(c.sphere_inlier_ratio), double(c.sphere_radius), double(c.footprint_fill),
                 double(c.side_face_ratio), int(c.upright), double(c.footprint_cover));
}

// Per-point and per-object counts of every method, the ceiling, and the --dump rows.
void CountObjects(const Evaluator& ev, const FrameId& id, const Frame& f, const Predictions& p,
                  Tally& tally) {
    auto& methods = tally.methods;
    for (std::size_t ob = 0; ob < f.perceived.objects.size(); ++ob) {
        std::array<std::size_t, kNumCategories> hist{};
        for (std::size_t k : f.ids[ob]) {
            for (Index i : f.parts[k]) {
                const int t = f.truth->data[i];
                if (t < 1 || t >= static_cast<int>(kNumCategories)) continue;
                ++hist[t];
                for (int m = 0; m < int(methods.size()); ++m) {
                    if (ev.set.Skip(m)) continue;
                    const bool per_part =
                        m == kPg || m == kVocabModelParts || m == kVocabStatsParts ||
                        (m >= kFirstVariant && (m - kFirstVariant) % kVariantRows == 0);
                    Category pred = per_part ? p.part[k][m] : p.object[ob][m];
                    if (m == kRules) pred = static_cast<Category>(f.perceived.point_categories[i]);
                    methods[m].AddPoint(t, pred);
                }
            }
        }
        const auto best = std::max_element(hist.begin(), hist.end()) - hist.begin();
        if (hist[best] == 0) continue;
        for (std::size_t t = 1; t < kNumCategories; ++t)
            tally.ceiling.Add(int(t), int(best), hist[t]);
        if (ev.dump && !f.ids[ob].empty()) WriteDumpRow(ev, id, f, p, ob, int(best));
        for (int m = 0; m < int(methods.size()); ++m) {
            if (ev.set.Skip(m)) continue;
            methods[m].object.Add(static_cast<int>(best), int(p.object[ob][m]));
        }
    }
}

// The votes of one scene's views in the world frame, and the single-view labels of their points.
struct SceneVotes {
    VoxelVoteGrid grid{0.005f}, grid_obj{0.005f}, grid_prod{0.005f}, grid_three{0.005f};
    std::vector<std::pair<std::vector<Eigen::Vector3f>, std::vector<int>>> kept;
    std::vector<std::vector<Category>> single, single_o, single_3;
};

// Adds the frame's labelled points to the vote grids; counts the per-part labels.
void CollectVotes(const Frame& f, const Predictions& p, const Eigen::Isometry3f& view, Tally& tally,
                  SceneVotes& sv) {
    std::vector<Eigen::Vector3f> world;
    std::vector<Distribution> votes, votes_o, votes_3;
    std::vector<int> truth;
    std::vector<Category> pred, pred_o, pred_3;
    for (std::size_t k = 0; k < f.parts.size(); ++k) {
        std::array<std::size_t, kNumCategories> hist{};
        const std::uint32_t ob = f.part_object[k];
        for (Index i : f.parts[k]) {
            const int t = f.truth->data[i];
            if (t < 1 || t >= static_cast<int>(kNumCategories)) continue;
            ++hist[t];
            world.push_back(view * f.scan.points[i]);
            votes.push_back(f.pg.part_probabilities[k]);
            truth.push_back(t);
            pred.push_back(f.pg.part_categories[k]);
            votes_o.push_back(p.merged[ob]);
            pred_o.push_back(ArgMaxCategory(p.merged[ob]));
            votes_3.push_back(p.three[ob]);
            pred_3.push_back(p.object[ob][kFusion3]);
        }
        const auto best = std::max_element(hist.begin(), hist.end()) - hist.begin();
        if (hist[best] > 0) tally.part.Add(static_cast<int>(best), int(f.pg.part_categories[k]));
    }
    sv.grid.Add(world, votes);
    sv.grid_obj.Add(world, votes_o);
    for (auto& vo : votes_o)
        for (float& x : vo) x = std::log(x + 0.01f) - std::log(0.01f);
    sv.grid_prod.Add(world, votes_o);
    sv.grid_three.Add(world, votes_3);
    sv.kept.emplace_back(std::move(world), std::move(truth));
    sv.single.push_back(std::move(pred));
    sv.single_o.push_back(std::move(pred_o));
    sv.single_3.push_back(std::move(pred_3));
}

// Counts the fused labels of all views' points against their single-view labels.
void CountMultiView(const SceneVotes& sv, Tally& tally) {
    for (std::size_t v = 0; v < sv.kept.size(); ++v) {
        const auto& [points, truth] = sv.kept[v];
        for (std::size_t i = 0; i < points.size(); ++i) {
            tally.multi.Add(truth[i], static_cast<int>(sv.grid.CategoryAt(points[i])));
            tally.single_in_multi.Add(truth[i], static_cast<int>(sv.single[v][i]));
            tally.multi_obj.Add(truth[i], static_cast<int>(sv.grid_obj.CategoryAt(points[i])));
            tally.single_obj.Add(truth[i], static_cast<int>(sv.single_o[v][i]));
            tally.multi_prod.Add(truth[i], static_cast<int>(sv.grid_prod.CategoryAt(points[i])));
            tally.multi_three.Add(truth[i], static_cast<int>(sv.grid_three.CategoryAt(points[i])));
            tally.single_three.Add(truth[i], static_cast<int>(sv.single_3[v][i]));
        }
    }
}

// Test scene `s`: six views, each perceived, categorised by every method and counted; prints the
// scene's line (and with --scene-matrices its objects and matrices).
void EvaluateScene(const Evaluator& ev, sim::ObjectSource& source, int s, Tally& tally) {
    const Options& o = ev.options;
    sim::TableSceneParams sp;
    sp.clutter = 0.6f;
    const sim::Scene scene = sim::MakeTableScene(sp, source, o.seed * 1000 + s);
    const sim::RayCaster caster(scene);
    const auto views = sim::TableViewpoints(scene, 6, {}, o.seed * 1000 + s);
    SceneVotes votes;
    for (std::size_t v = 0; v < views.size(); ++v) {
        Frame f;
        PerceiveFrame(ev, caster, views[v], o.seed * 7919 + s * 10 + v, tally, f);
        Predictions p;
        p.part.assign(f.parts.size(), std::vector<Category>(tally.methods.size(), Category::kNone));
        p.object.assign(f.perceived.objects.size(),
                        std::vector<Category>(tally.methods.size(), Category::kNone));
        for (std::size_t k = 0; k < f.parts.size(); ++k) p.part[k][kPg] = f.pg.part_categories[k];
        PredictVariants(ev, f, p);
        BaselineParts b;
        if (o.baselines) PredictBaselineParts(ev, f, views[v], b, p);
        PredictObjects(ev, f, b, p);
        CountObjects(ev, FrameId{s, v, &scene}, f, p, tally);
        CollectVotes(f, p, views[v], tally, votes);
    }
    CountMultiView(votes, tally);
    auto& methods = tally.methods;
    if (o.scene_matrices) {
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
                scene.objects.size(), tally.frames, methods[kPg].scene_accuracy.back(),
                methods[kRules].scene_accuracy.back());
    std::fflush(stdout);
}

// ---------------------------------------------------------------------------------------------
// The report.

void PrintMatrices(const MethodSet& set, const Tally& tally) {
    for (int m = 0; m < int(tally.methods.size()); ++m) {
        if (set.Skip(m)) continue;
        PrintConfusion("per point, " + tally.methods[m].name, tally.methods[m].point);
        PrintConfusion("per object, " + tally.methods[m].name, tally.methods[m].object);
    }
    PrintConfusion("per part (segment), part-graph hashing", tally.part);
}

void PrintSummary(const Options& o, const MethodSet& set, const Tally& tally) {
    const auto& methods = tally.methods;
    std::printf("\nsummary over %d scenes (%zu points, %zu perceived objects with a category):\n",
                o.scenes, Scored(methods[kPg].point), Scored(methods[kPg].object));
    std::printf("%-56s %9s %9s %19s %9s %s\n", "method", "per point", "per object",
                "per scene mean+-sd", "balanced", "worst category (per point)");
    for (int m = 0; m < int(methods.size()); ++m) {
        if (set.Skip(m)) continue;
        const auto [mean, sd] = MeanStd(methods[m].scene_accuracy);
        const Balanced b = BalancedAccuracy(methods[m].point);
        std::printf("%-56s %9.3f %9.3f %11.3f +- %.3f %9.3f %s %.3f\n", methods[m].name.c_str(),
                    Accuracy(methods[m].point), Accuracy(methods[m].object), mean, sd, b.mean,
                    b.worst.c_str(), b.worst_share);
    }
    std::printf("per part (segment), part-graph hashing: %.3f\n", Accuracy(tally.part));
    std::printf(
        "ceiling of per-object labels (each perceived object named by its points' majority "
        "truth): %.3f per point\n",
        Accuracy(tally.ceiling));
    std::printf("multi-view (6 views, 5 mm voxel votes): %.3f per point vs %.3f single views\n",
                Accuracy(tally.multi), Accuracy(tally.single_in_multi));
    std::printf(
        "multi-view, object votes (each point votes with its object's distribution, as perceive "
        "--manifest fuses): %.3f per point vs %.3f single views\n",
        Accuracy(tally.multi_obj), Accuracy(tally.single_obj));
    std::printf("multi-view, object votes, product rule: %.3f per point vs %.3f single views\n",
                Accuracy(tally.multi_prod), Accuracy(tally.single_obj));
    std::printf(
        "multi-view, object votes of part-graph+rules+cluster: %.3f per point vs %.3f single "
        "views\n",
        Accuracy(tally.multi_three), Accuracy(tally.single_three));
    const double frames = double(std::max<std::size_t>(tally.frames, 1));
    std::printf(
        "categorising all parts of a 640x480 frame: %.1f ms mean over %zu frames "
        "(%.1f parts per frame; graph, GRSD- and votes; 1 thread)\n",
        tally.recog_ms / frames, tally.frames, double(tally.parts_total) / frames);
}

// The test objects: the odd-indexed library meshes (even ones with --even-test), else procedural.
void MakeTestSource(const Options& o, bool library, std::optional<sim::ObjectSource>& source) {
    if (library && !o.procedural_test) {
        auto all = sim::ReadMeshLibrary(o.meshes, sim::TabletopCategories());
        std::vector<sim::MeshEntry> test;
        for (std::size_t i = o.even_test ? 0 : 1; i < all.size(); i += 2) test.push_back(all[i]);
        source.emplace(std::move(test), false);
    } else {
        source.emplace();
    }
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    std::vector<Variant> variants;
    if (const auto status = ParseOptions(argc, argv, o, variants)) return *status;
    std::FILE* dump = o.dump_path.empty() ? nullptr : std::fopen(o.dump_path.c_str(), "w");
    if (!o.dump_path.empty() && !dump) {
        std::fprintf(stderr, "part_graph_eval: cannot write %s\n", o.dump_path.c_str());
        return 2;
    }
    const bool descriptor_variants =
        std::any_of(variants.begin(), variants.end(), [](const Variant& v) { return v.own_model; });
    Training t;
    TrainModel(o, o.baselines || descriptor_variants, t);
    Baselines baselines;
    if (o.baselines) TrainBaselines(o, t, baselines);
    const auto variant_models = TrainVariantModels(variants, t);

    std::optional<sim::ObjectSource> source;
    MakeTestSource(o, t.library, source);
    Evaluator ev{o, t.model, baselines, variants, variant_models, {}, {}, {}, dump};
    ev.set.num_methods = o.baselines ? int(kNumMethods) : int(kVocabModelParts);
    ev.set.stacked = t.model.stacker.trained();
    ev.experts = ev.perceive.category;
    ev.experts.part_graph = o.recognition;
    ev.experts.expert_weights = o.expert_weights;
    Tally tally;
    tally.methods = MakeMethods(o, variants);
    for (int s = 0; s < o.scenes; ++s) EvaluateScene(ev, *source, s, tally);
    if (o.matrices) PrintMatrices(ev.set, tally);
    PrintSummary(o, ev.set, tally);
    if (dump) std::fclose(dump);
    return 0;
}
