// Parts per object (thesis section 5.4.1, Eq. 5.1): runs perceive on simulated frames with ground
// truth (`multicue simulate scenes` output: fields label and category) and counts the
// region-growing parts of every perceived object that is one ground-truth object (purity >= 0.9,
// recall >= 0.8), per object type (flat: box, flat, plate; round: sphere, cylinder; other).
// The Poisson mean of a type is the mean count (maximum likelihood); the variance shows how
// Poisson-like the counts are. Perceived objects that cover two or more ground-truth objects
// (each at least half) are counted apart: their parts are what the model must call "several".
// The printed means are the defaults of PartCountParams.
//
// usage: part_counts FRAME.pcd [FRAME.pcd ...]

#include <array>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "driver_options.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/reconstruction/part_count_model.hpp"
#include "multicue/system/perceive.hpp"

using namespace multicue;

int main(int argc, char** argv) {
    std::vector<std::string> frames;
    CLI::App app{
        "part_counts: parts per perceived object on simulated frames with ground truth (the "
        "label and category fields of multicue simulate scenes): the Poisson means of thesis "
        "section 5.4.1"};
    app.add_option("FRAMES", frames, "simulated frames (.pcd)")->required();
    if (auto code = eval::ParseDriverOptions(app, "part_counts", [&] { app.parse(argc, argv); }))
        return *code;
    constexpr std::array<const char*, 3> kTypes{"flat", "round", "other"};
    std::array<std::vector<std::size_t>, 3> single;
    std::array<std::vector<std::size_t>, 3> merged;
    PerceiveParams params;
    params.models.touching.enabled = params.models.stacked.enabled =
        params.models.concentric.enabled = false;
    for (std::size_t a = 0; a < frames.size(); ++a) {
        PointCloud cloud;
        try {
            cloud = io::ReadPcd(frames[a]);
        } catch (const Error& e) {
            std::fprintf(stderr, "part_counts: %s\n", e.what());
            return 1;
        }
        const auto* truth = cloud.FindExtraField("category");
        if (cloud.labels.size() != cloud.size() || truth == nullptr || truth->size != 1) {
            std::fprintf(stderr, "part_counts: %s has no label and u8 category fields\n",
                         frames[a].c_str());
            return 1;
        }
        const PerceiveResult r = Perceive(cloud, params);
        std::map<std::uint32_t, std::size_t> gt_size;
        std::map<std::uint32_t, std::array<std::size_t, kNumCategories>> gt_category;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const std::uint32_t g = cloud.labels[i];
            if (g < 20 || !cloud.IsFinite(i)) continue;
            ++gt_size[g];
            const std::uint8_t c = truth->data[i];
            if (c < kNumCategories) ++gt_category[g][c];
        }
        for (const auto& o : r.objects) {
            std::map<std::uint32_t, std::size_t> hist;
            for (Index i : o.indices) {
                if (cloud.labels[i] >= 20) ++hist[cloud.labels[i]];
            }
            std::uint32_t best = 0;
            std::size_t count = 0, covered = 0;
            for (const auto& [g, n] : hist) {
                if (n > count) {
                    best = g;
                    count = n;
                }
                if (2 * n >= gt_size[g]) ++covered;
            }
            if (best == 0) continue;
            const auto& h = gt_category[best];
            const auto c = static_cast<Category>(std::max_element(h.begin(), h.end()) - h.begin());
            const auto type = static_cast<std::size_t>(ObjectTypeOf(c));
            if (covered >= 2) {
                merged[type].push_back(o.parts.size());
            } else if (10 * count >= 9 * o.indices.size() && 10 * count >= 8 * gt_size[best]) {
                single[type].push_back(o.parts.size());
            }
        }
        std::fprintf(stderr, "\r%zu / %zu frames", a + 1, frames.size());
    }
    std::fprintf(stderr, "\n");
    for (std::size_t t = 0; t < 3; ++t) {
        const auto& v = single[t];
        double mean = 0.0, var = 0.0;
        for (std::size_t n : v) mean += static_cast<double>(n);
        mean = v.empty() ? 0.0 : mean / static_cast<double>(v.size());
        for (std::size_t n : v)
            var += (static_cast<double>(n) - mean) * (static_cast<double>(n) - mean);
        var = v.size() > 1 ? var / static_cast<double>(v.size() - 1) : 0.0;
        std::map<std::size_t, std::size_t> histogram;
        for (std::size_t n : v) ++histogram[n];
        std::printf(
            "%-6s one object: %4zu objects, mean parts (lambda) %.3f, variance %.3f; counts:",
            kTypes[t], v.size(), mean, var);
        for (const auto& [n, k] : histogram) std::printf(" %zu:%zu", n, k);
        double merged_mean = 0.0;
        for (std::size_t n : merged[t]) merged_mean += static_cast<double>(n);
        std::printf("\n%-6s several:    %4zu objects, mean parts %.3f\n", kTypes[t],
                    merged[t].size(), merged[t].empty() ? 0.0 : merged_mean / merged[t].size());
    }
    return 0;
}
