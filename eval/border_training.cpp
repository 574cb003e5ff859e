// Learns the decision whether two neighbouring parts of an object hypothesis are one object
// (segmentation/border_classifier.hpp; thesis sections 4.2.1, 5.1.1, 5.4.1): perceive's stages
// up to the parts (table, normals, hypotheses, region growing, folded parts cut) run on labelled
// frames; every border between two large parts becomes a row of its features with the truth
// "same object" (both parts' majority labels equal). A logistic regression (standardised
// inputs, L2, Newton steps) is fitted on the training frames and written as a perceive
// parameter file; the validation frames are segmented up to the concave split with the rules
// and with the fitted classifier, and scored per ground-truth object (share matched with
// F >= 0.75 by the best group, before categories and models).
//
// Frames: `multicue simulate scenes` output (objects labelled 10 and above) or mOSD frames
// (objects labelled 20 and above, the object being label / 10), one file or a folder of .pcd.
//
// usage: border_training --train PATH... [--validate PATH...] [--out FILE.json] [--l2 0.01]
//                        [--threshold 0.9] [--rows FILE.csv]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "driver_options.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/segmentation/border_classifier.hpp"
#include "multicue/system/perceive.hpp"

using namespace multicue;
namespace fs = std::filesystem;

namespace {

// Ground-truth object of every point: simulated frames have a category field and objects from
// label 10, mOSD frames objects from label 20 (object = label / 10); 0 = no object.
std::vector<std::uint32_t> TruthObjects(const PointCloud& cloud) {
    const bool sim = cloud.FindExtraField("category") != nullptr;
    std::vector<std::uint32_t> out(cloud.size(), 0);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const std::uint32_t l = cloud.labels[i];
        if (!cloud.IsFinite(i)) continue;
        if (sim && l >= 10) out[i] = l;
        if (!sim && l >= 20) out[i] = l / 10;
    }
    return out;
}

std::uint32_t Majority(const Indices& pts, const std::vector<std::uint32_t>& truth) {
    std::map<std::uint32_t, std::size_t> h;
    for (Index i : pts) ++h[truth[i]];
    std::uint32_t best = 0;
    std::size_t count = 0;
    for (const auto& [g, n] : h) {
        if (n > count) {
            count = n;
            best = g;
        }
    }
    return best;
}

struct Frame {
    PointCloud cloud;
    bool simulated = true;
    std::vector<std::uint32_t> truth;
    Eigen::Vector4f plane = Eigen::Vector4f::Zero();
    std::vector<Indices> hypotheses;
    std::vector<std::vector<Indices>> parts;  // region-growing parts of each hypothesis
};

// Perceive's stages up to the parts of every hypothesis (no concave split).
Frame Prepare(const fs::path& file, const PerceiveParams& params) {
    Frame fr;
    fr.cloud = io::ReadPcd(file);
    if (fr.cloud.labels.size() != fr.cloud.size()) {
        throw DataError(fmt::format("{} has no label field", file.string()));
    }
    fr.truth = TruthObjects(fr.cloud);
    fr.simulated = fr.cloud.FindExtraField("category") != nullptr;
    TableRegion table = FindTableRegion(fr.cloud, params.support, params.prism);
    if (!table.support.found) return fr;
    fr.plane = table.support.plane;
    EnsureFrameNormals(fr.cloud, table.points, params.normals);
    const auto clusters = ClusterObjects(fr.cloud, table.points, params.clustering);
    PartSegmentationParams pp = params.parts;
    pp.convexity.enabled = false;
    for (auto& o :
         SegmentParts(fr.cloud, clusters.clusters, fr.plane, pp, params.clustering.min_points)
             .objects) {
        fr.hypotheses.push_back(std::move(o.indices));
        fr.parts.push_back(std::move(o.parts));
    }
    return fr;
}

// Rows of every border between two large parts of the frame's hypotheses.
void AddRows(const Frame& fr, const ConvexitySplitParams& cp, double real_weight,
             std::vector<BorderExample>& rows) {
    const PartBorderParams bp{.patch_size = cp.patch_size, .smooth_angle_deg = cp.smooth_angle_deg};
    for (std::size_t h = 0; h < fr.hypotheses.size(); ++h) {
        const Indices& object = fr.hypotheses[h];
        std::vector<Indices> parts = fr.parts[h];
        if (parts.size() < 2) continue;
        PartBorders borders = ComputePartBorders(fr.cloud, object, parts, bp, fr.plane);
        if (cp.fold.enabled) {
            parts = SplitFoldedParts(fr.cloud, object, parts, borders, cp.fold);
            borders = ComputePartBorders(fr.cloud, object, parts, bp, fr.plane);
        }
        const auto summaries = SummarizeParts(parts, borders, fr.plane);
        for (const PartBorder& b : borders.borders) {
            if (parts[b.a].size() < cp.classifier.large_part_points ||
                parts[b.b].size() < cp.classifier.large_part_points || b.pairs < cp.min_border) {
                continue;
            }
            const std::uint32_t ga = Majority(parts[b.a], fr.truth);
            const std::uint32_t gb = Majority(parts[b.b], fr.truth);
            if (ga == 0 || gb == 0) continue;
            rows.push_back({ComputeBorderFeatures(b, borders, summaries, fr.plane.head<3>()),
                            ga == gb, fr.simulated ? 1.0 : real_weight});
        }
    }
}

// Share of the frame's ground-truth objects that one object of `objects` matches with F >= 0.75.
std::pair<std::size_t, std::size_t> Score(const Frame& fr, const std::vector<Indices>& objects) {
    std::map<std::uint32_t, std::size_t> size;
    for (std::uint32_t g : fr.truth) {
        if (g != 0) ++size[g];
    }
    std::map<std::uint32_t, double> best;
    for (const Indices& o : objects) {
        std::map<std::uint32_t, std::size_t> inter;
        for (Index i : o) {
            if (fr.truth[i] != 0) ++inter[fr.truth[i]];
        }
        for (const auto& [g, c] : inter) {
            const double p = static_cast<double>(c) / static_cast<double>(o.size());
            const double r = static_cast<double>(c) / static_cast<double>(size[g]);
            best[g] = std::max(best[g], 2.0 * p * r / (p + r));
        }
    }
    std::size_t ok = 0;
    for (const auto& [g, n] : size) ok += best[g] >= 0.75 ? 1 : 0;
    return {ok, size.size()};
}

double Validate(const std::vector<Frame>& frames, const ConvexitySplitParams& cp,
                std::size_t min_points) {
    std::size_t ok = 0, total = 0;
    for (const Frame& fr : frames) {
        std::vector<Indices> objects;
        for (std::size_t h = 0; h < fr.hypotheses.size(); ++h) {
            ConvexitySplitParams p = cp;
            p.min_object_points = min_points;
            auto r = SplitByConvexity(fr.cloud, fr.hypotheses[h], fr.parts[h], p, fr.plane);
            for (auto& o : r.objects) {
                if (o.size() >= min_points) objects.push_back(std::move(o));
            }
        }
        const auto [k, n] = Score(fr, objects);
        ok += k;
        total += n;
    }
    return total == 0 ? 0.0 : static_cast<double>(ok) / static_cast<double>(total);
}

std::vector<fs::path> Expand(const std::vector<std::string>& paths) {
    std::vector<fs::path> out;
    for (const auto& p : paths) {
        if (fs::is_directory(p)) {
            std::vector<fs::path> files;
            for (const auto& e : fs::directory_iterator(p)) {
                if (e.path().extension() == ".pcd") files.push_back(e.path());
            }
            std::sort(files.begin(), files.end());
            out.insert(out.end(), files.begin(), files.end());
        } else {
            out.emplace_back(p);
        }
    }
    return out;
}

std::vector<Frame> Load(const std::vector<fs::path>& files, const PerceiveParams& params,
                        const char* what) {
    std::vector<Frame> frames;
    for (std::size_t k = 0; k < files.size(); ++k) {
        frames.push_back(Prepare(files[k], params));
        std::fprintf(stderr, "\r%s: %zu / %zu frames", what, k + 1, files.size());
    }
    if (!files.empty()) std::fprintf(stderr, "\n");
    return frames;
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string> train, validate;
    std::string out_file, rows_file;
    double l2 = 0.01;
    double real_weight = 3.0;
    float threshold = BorderClassifierParams{}.threshold;
    CLI::App app{
        "border_training: fits the border classifier of the concave split (same object or "
        "two) on labelled frames and scores the grouping on validation frames"};
    app.add_option("--train", train, "training frames (.pcd files or folders)")->required();
    app.add_option("--validate", validate, "validation frames (.pcd files or folders)");
    app.add_option("--out", out_file, "write the fitted classifier as a perceive parameter file");
    app.add_option("--rows", rows_file, "write the training rows as CSV");
    app.add_option("--l2", l2, "L2 penalty on the standardised weights")
        ->check(CLI::NonNegativeNumber);
    app.add_option("--real-weight", real_weight,
                   "weight of a row from a real (mOSD) frame; simulated rows weigh 1")
        ->check(CLI::NonNegativeNumber);
    app.add_option("--threshold", threshold, "join threshold written with the weights")
        ->check(CLI::Range(0.01, 0.99));
    if (auto code =
            eval::ParseDriverOptions(app, "border_training", [&] { app.parse(argc, argv); }))
        return *code;
    try {
        PerceiveParams params;
        const std::vector<Frame> train_frames = Load(Expand(train), params, "train");
        std::vector<BorderExample> rows;
        for (const Frame& fr : train_frames) AddRows(fr, params.parts.convexity, real_weight, rows);
        std::size_t same = 0;
        for (const BorderExample& r : rows) same += r.same ? 1 : 0;
        std::printf("training rows: %zu (same object %zu, two objects %zu)\n", rows.size(), same,
                    rows.size() - same);
        if (rows.empty() || same == 0 || same == rows.size()) {
            std::fprintf(stderr, "border_training: need rows of both kinds\n");
            return 1;
        }
        BorderClassifierParams fitted = params.parts.convexity.classifier;
        fitted.threshold = threshold;
        fitted = FitBorderClassifier(rows, l2, fitted);
        std::printf("bias %.6g\n", fitted.bias);
        for (std::size_t k = 0; k < kBorderFeatureCount; ++k) {
            std::printf("%-20s %+.6g\n", std::string(kBorderFeatureNames[k]).c_str(),
                        fitted.weights[k]);
        }
        if (!rows_file.empty()) {
            std::string csv;
            for (const auto& name : kBorderFeatureNames) csv += fmt::format("{},", name);
            csv += "same\n";
            for (const BorderExample& r : rows) {
                for (float v : r.features) csv += fmt::format("{},", v);
                csv += r.same ? "1\n" : "0\n";
            }
            io::WriteFileAtomically(rows_file, [&](std::ostream& o) { o << csv; });
        }
        if (!out_file.empty()) {
            std::string json = fmt::format(
                "{{\"parts\": {{\"convexity\": {{\"learned\": true, \"classifier\": {{"
                "\"threshold\": {}, \"bias\": {:.6g}, \"weights\": {{",
                fitted.threshold, fitted.bias);
            for (std::size_t k = 0; k < kBorderFeatureCount; ++k) {
                json += fmt::format("{}\"{}\": {:.6g}", k ? ", " : "", kBorderFeatureNames[k],
                                    fitted.weights[k]);
            }
            json += "}}}}}\n";
            io::WriteFileAtomically(out_file, [&](std::ostream& o) { o << json; });
        }
        // Each validation path on its own: the rules, then the classifier at several thresholds.
        for (const std::string& path : validate) {
            const std::vector<Frame> val_frames = Load(Expand({path}), params, "validate");
            if (val_frames.empty()) continue;
            ConvexitySplitParams rules = params.parts.convexity;
            rules.learned = false;
            const std::size_t min_points = params.clustering.min_points;
            std::printf(
                "%s: objects matched with F >= 0.75 before categories and models: rules "
                "%.4f; learned",
                path.c_str(), Validate(val_frames, rules, min_points));
            for (float t : {0.5f, 0.7f, 0.8f, 0.85f, 0.9f, 0.95f}) {
                ConvexitySplitParams learned = params.parts.convexity;
                learned.classifier = fitted;
                learned.classifier.threshold = t;
                std::printf(" %.2f: %.4f", t, Validate(val_frames, learned, min_points));
            }
            std::printf("\n");
        }
    } catch (const Error& e) {
        std::fprintf(stderr, "border_training: %s\n", e.what());
        return 1;
    }
    return 0;
}
