#include "multicue/training/kitchen_scan_truth.hpp"

#include <algorithm>
#include <cstring>

namespace multicue::training {
namespace {

template <typename T>
std::vector<T> ReadField(const PointCloud& c, const char* name) {
    std::vector<T> out(c.size(), 0);
    const ExtraField* f = c.FindExtraField(name);
    if (f && f->data.size() == c.size() * sizeof(T)) {
        std::memcpy(out.data(), f->data.data(), f->data.size());
    }
    return out;
}

}  // namespace

ScanTruth::ScanTruth(const PointCloud& scan)
    : semantic(ReadField<std::uint8_t>(scan, "semantic")),
      model(ReadField<std::uint16_t>(scan, "model")),
      link(ReadField<std::uint16_t>(scan, "link")),
      joint(ReadField<std::uint16_t>(scan, "joint")) {}

std::map<std::uint32_t, TrueFront> TrueFronts(const PointCloud& scan, const ScanTruth& t) {
    std::map<std::uint32_t, TrueFront> out;
    std::map<std::uint32_t, std::map<int, std::size_t>> joints;
    for (std::size_t i = 0; i < scan.size(); ++i) {
        if (!scan.IsFinite(i) || t.model[i] == 0) continue;
        const sim::KitchenClass c = t.Class(i);
        const std::uint32_t k = t.Key(i);
        if (t.IsFront(i)) {
            out[k].key = k;
            ++out[k].points;
            ++joints[k][static_cast<int>(t.joint[i]) - 1];
        } else if (c == sim::KitchenClass::kHandle || c == sim::KitchenClass::kKnob) {
            out[k].key = k;
            ++out[k].fixture_points;
        }
    }
    for (auto& [k, f] : out) {
        std::size_t best = 0;
        for (const auto& [j, n] : joints[k]) {
            if (n > best) {
                best = n;
                f.joint = j;
            }
        }
    }
    return out;
}

std::map<std::uint32_t, std::pair<int, float>> MatchFronts(
    const mapping::KitchenMap& map, const ScanTruth& t,
    const std::map<std::uint32_t, TrueFront>& truth, std::size_t offset) {
    struct Pair {
        float iou;
        int pred;
        std::uint32_t key;
    };
    std::vector<Pair> pairs;
    for (std::size_t f = 0; f < map.fronts.size(); ++f) {
        std::map<std::uint32_t, std::size_t> hits;
        std::size_t size = 0;
        for (const Index gi : map.fronts[f].indices) {
            if (gi < offset || gi - offset >= t.semantic.size()) continue;
            const std::size_t i = gi - offset;
            ++size;
            if (t.IsFront(i)) ++hits[t.Key(i)];
        }
        for (const auto& [k, n] : hits) {
            const auto it = truth.find(k);
            if (it == truth.end() || it->second.points == 0) continue;
            const float iou =
                static_cast<float>(n) / static_cast<float>(size + it->second.points - n);
            pairs.push_back({iou, static_cast<int>(f), k});
        }
    }
    std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
        return a.iou != b.iou ? a.iou > b.iou : a.pred < b.pred;
    });
    std::map<std::uint32_t, std::pair<int, float>> out;
    std::vector<bool> used(map.fronts.size(), false);
    for (const Pair& p : pairs) {
        if (used[static_cast<std::size_t>(p.pred)] || out.count(p.key)) continue;
        used[static_cast<std::size_t>(p.pred)] = true;
        out[p.key] = {p.pred, p.iou};
    }
    return out;
}

std::map<int, int> FurnitureInstances(const mapping::KitchenMap& map, const PointCloud& scan,
                                      float min_iou) {
    const ScanTruth t(scan);
    const auto fronts = TrueFronts(scan, t);
    std::map<int, std::map<int, std::size_t>> votes;  // furniture -> instance -> points
    for (const auto& [key, m] : MatchFronts(map, t, fronts)) {
        if (m.second < min_iou) continue;
        const int furniture = map.fronts[static_cast<std::size_t>(m.first)].furniture;
        if (furniture < 0) continue;
        votes[furniture][static_cast<int>(key >> 16) - 1] += fronts.at(key).points;
    }
    std::map<int, int> out;
    for (const auto& [furniture, v] : votes) out[furniture] = MostVoted(v);
    return out;
}

int MostVoted(const std::map<int, std::size_t>& votes) {
    int best = -1;
    std::size_t n = 0;
    for (const auto& [key, c] : votes) {
        if (c > n) {
            n = c;
            best = key;
        }
    }
    return best;
}

}  // namespace multicue::training
