#include "multicue/recognition/furniture_voting.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

// The summed votes of one class on a grid of cells over the floor.
struct VoteGrid {
    Eigen::Vector2f origin = Eigen::Vector2f::Zero();  ///< centre of cell (0, 0)
    float cell = 0.05f;
    int nx = 0, ny = 0;
    std::vector<double> sum;  ///< (nx + 1) x (ny + 1) summed-area table

    int Cx(float x) const { return static_cast<int>(std::lround((x - origin.x()) / cell)); }
    int Cy(float y) const { return static_cast<int>(std::lround((y - origin.y()) / cell)); }
    // Votes in cells [x0, x1] x [y0, y1] (clamped).
    double Window(int x0, int y0, int x1, int y1) const {
        x0 = std::max(x0, 0), y0 = std::max(y0, 0);
        x1 = std::min(x1, nx - 1), y1 = std::min(y1, ny - 1);
        if (x0 > x1 || y0 > y1) return 0.0;
        auto at = [&](int x, int y) { return sum[static_cast<std::size_t>(x) * (ny + 1) + y]; };
        return at(x1 + 1, y1 + 1) - at(x0, y1 + 1) - at(x1 + 1, y0) + at(x0, y0);
    }
};

VoteGrid BuildGrid(const std::vector<const FurnitureVote*>& votes, float cell, float scale) {
    VoteGrid g;
    g.cell = cell;
    Eigen::Vector2f lo(std::numeric_limits<float>::infinity(),
                       std::numeric_limits<float>::infinity());
    Eigen::Vector2f hi = -lo;
    for (const auto* v : votes) {
        lo = lo.cwiseMin(v->x.head<2>());
        hi = hi.cwiseMax(v->x.head<2>());
    }
    g.origin = lo;
    g.nx = g.Cx(hi.x()) + 1;
    g.ny = g.Cy(hi.y()) + 1;
    std::vector<double> cells(static_cast<std::size_t>(g.nx) * g.ny, 0.0);
    for (const auto* v : votes) {
        cells[static_cast<std::size_t>(g.Cx(v->x.x())) * g.ny + g.Cy(v->x.y())] +=
            v->weight * scale;
    }
    g.sum.assign(static_cast<std::size_t>(g.nx + 1) * (g.ny + 1), 0.0);
    for (int x = 0; x < g.nx; ++x) {
        double row = 0.0;
        for (int y = 0; y < g.ny; ++y) {
            row += cells[static_cast<std::size_t>(x) * g.ny + y];
            g.sum[static_cast<std::size_t>(x + 1) * (g.ny + 1) + y + 1] =
                g.sum[static_cast<std::size_t>(x) * (g.ny + 1) + y + 1] + row;
        }
    }
    return g;
}

// Section 4.2.4.2: two hypotheses of one class are inconsistent when the footprints of objects
// centred there (discs of the class width) overlap; the stronger one stays.
std::vector<FurnitureHypothesis> Consistent(std::vector<FurnitureHypothesis> out,
                                            const FurnitureModel& model, bool cross_class) {
    std::vector<FurnitureHypothesis> consistent;
    for (auto& hyp : out) {
        const float w = model.classes()[static_cast<std::size_t>(hyp.cls)].width;
        bool ok = true;
        for (const auto& k : consistent) {
            if (k.cls == hyp.cls) {
                ok = ok && (k.centre - hyp.centre).norm() >= w;
            } else if (cross_class) {
                const float wk = model.classes()[static_cast<std::size_t>(k.cls)].width;
                ok = ok && (k.centre - hyp.centre).norm() >= (w + wk) / 2;
            }
        }
        if (ok) consistent.push_back(std::move(hyp));
    }
    return consistent;
}

}  // namespace

const char* FurnitureVoteNormalizationName(FurnitureVoteNormalization n) {
    switch (n) {
        case FurnitureVoteNormalization::kPerClass:
            return "per-class";
        case FurnitureVoteNormalization::kPerWord:
            return "per-word";
        case FurnitureVoteNormalization::kBalanced:
            return "balanced";
    }
    return "per-class";
}

FurnitureVoteNormalization ParseFurnitureVoteNormalization(std::string_view name) {
    if (name == "per-class") return FurnitureVoteNormalization::kPerClass;
    if (name == "per-word") return FurnitureVoteNormalization::kPerWord;
    if (name == "balanced") return FurnitureVoteNormalization::kBalanced;
    throw InvalidArgument(
        fmt::format("vote normalization must be per-class, per-word or balanced, got '{}'", name));
}

void FurnitureVotingParams::Validate() const {
    if (activations < 1) throw InvalidArgument("furniture voting: activations must be >= 1");
    if (!(extent_margin > 0.0f) || !std::isfinite(extent_margin)) {
        throw InvalidArgument(
            fmt::format("furniture voting: extent_margin must be > 0, got {}", extent_margin));
    }
    if (!std::isfinite(height_margin))
        throw InvalidArgument("furniture voting: height_margin must be finite");
    if (!(max_height_error >= 0.0f) || !std::isfinite(max_height_error)) {
        throw InvalidArgument(fmt::format("furniture voting: max_height_error must be >= 0, got {}",
                                          max_height_error));
    }
}

std::vector<FurnitureVote> CastFurnitureVotes(const FurnitureParts& parts,
                                              const FurnitureModel& model, int view,
                                              const FurnitureVotingParams& params) {
    params.Validate();
    if (!model.trained()) throw InvalidArgument("furniture voting: the model is not trained");
    std::vector<FurnitureVote> votes;
    // Class shares of the training parts (balanced normalisation).
    const std::size_t n_classes = model.classes().size();
    std::vector<float> share(n_classes, 0.0f);
    for (const auto& p : model.parts()) share[static_cast<std::size_t>(p.cls)] += 1.0f;
    for (float& s : share) s = s / static_cast<float>(model.parts().size());
    const float max_extent = params.extent_margin * model.max_part_extent();
    const float max_top = model.max_object_height() + params.height_margin;
    for (std::size_t k = 0; k < parts.parts.size(); ++k) {
        const FurniturePart& part = parts.parts[k];
        if (part.extent > max_extent || part.top > max_top) continue;
        if (!part.features.allFinite()) continue;
        const Eigen::Matrix3f R =
            Eigen::AngleAxisf(part.frame_yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
        const auto act =
            model.Activate({part.features.data(), static_cast<std::size_t>(part.features.size())},
                           params.activation, params.activations);
        for (const auto& [a, p] : act) {
            auto vote = [&](int element, float weight) {
                const FurnitureTrainingPart& e = model.parts()[static_cast<std::size_t>(element)];
                const Eigen::Vector3f x = part.centroid + R * e.offset;
                if (params.max_height_error > 0.0f &&
                    std::abs(x.z() - e.centre_z) > params.max_height_error) {
                    return;
                }
                votes.push_back({x, weight, e.cls, static_cast<int>(k), view});
            };
            if (params.activation == FurnitureActivation::kNearestPart) {
                vote(a, p);
                continue;
            }
            // Eq. (4.4): each element of class o in word A_i carries 1 / #(A_i, o).
            const auto& elements = model.WordElements(a);
            float total = 0.0f;  // the word's weighted element count (per-word normalisations)
            if (params.normalization != FurnitureVoteNormalization::kPerClass) {
                for (std::size_t c = 0; c < n_classes; ++c) {
                    const float n = model.WordClassCount(a, static_cast<int>(c));
                    total +=
                        params.normalization == FurnitureVoteNormalization::kBalanced && n > 0.0f
                            ? n / share[c]
                            : n;
                }
            }
            for (int e : elements) {
                const auto cls =
                    static_cast<std::size_t>(model.parts()[static_cast<std::size_t>(e)].cls);
                switch (params.normalization) {
                    case FurnitureVoteNormalization::kPerClass:
                        vote(e, p / model.WordClassCount(a, static_cast<int>(cls)));
                        break;
                    case FurnitureVoteNormalization::kPerWord:
                        vote(e, p / total);
                        break;
                    case FurnitureVoteNormalization::kBalanced:
                        vote(e, p / (share[cls] * total));
                        break;
                }
            }
        }
    }
    return votes;
}

void FurnitureSelectionParams::Validate() const {
    if (!(cell > 0.0f) || !std::isfinite(cell)) {
        throw InvalidArgument(fmt::format("furniture selection: cell must be > 0, got {}", cell));
    }
    if (!(window_scale > 0.0f) || !std::isfinite(window_scale)) {
        throw InvalidArgument(
            fmt::format("furniture selection: window_scale must be > 0, got {}", window_scale));
    }
    if (!(threshold_scale >= 0.0f) || !std::isfinite(threshold_scale)) {
        throw InvalidArgument(fmt::format(
            "furniture selection: threshold_scale must be >= 0, got {}", threshold_scale));
    }
    if (!(other_classes_from >= 0.0f) || !std::isfinite(other_classes_from)) {
        throw InvalidArgument(fmt::format(
            "furniture selection: other_classes_from must be >= 0, got {}", other_classes_from));
    }
    if (!(min_part_share >= 0.0f && min_part_share <= 1.0f)) {
        throw InvalidArgument(fmt::format(
            "furniture selection: min_part_share must be in [0, 1], got {}", min_part_share));
    }
}

std::vector<FurnitureHypothesis> SelectFurnitureHypotheses(const std::vector<FurnitureVote>& votes,
                                                           int views, const FurnitureModel& model,
                                                           const FurnitureSelectionParams& params) {
    params.Validate();
    if (views < 1)
        throw InvalidArgument(
            fmt::format("furniture selection: views must be >= 1, got {}", views));
    const int n_classes = static_cast<int>(model.classes().size());
    std::vector<std::vector<const FurnitureVote*>> by_class(static_cast<std::size_t>(n_classes));
    for (const auto& v : votes) {
        if (v.cls < 0 || v.cls >= n_classes) {
            throw InvalidArgument(
                fmt::format("furniture selection: vote of unknown class {}", v.cls));
        }
        if (v.weight > 0.0f && v.x.allFinite())
            by_class[static_cast<std::size_t>(v.cls)].push_back(&v);
    }
    const float scale = 1.0f / static_cast<float>(views);
    std::vector<FurnitureHypothesis> out;
    std::vector<VoteGrid> grids(static_cast<std::size_t>(n_classes));
    auto half_window = [&](const FurnitureClass& cls) {
        return std::max(
            1, static_cast<int>(std::lround(params.window_scale * cls.width / 2 / params.cell)));
    };
    for (int c = 0; c < n_classes; ++c) {
        const auto& cv = by_class[static_cast<std::size_t>(c)];
        if (cv.empty()) continue;
        const FurnitureClass& cls = model.classes()[static_cast<std::size_t>(c)];
        grids[static_cast<std::size_t>(c)] = BuildGrid(cv, params.cell, scale);
        const VoteGrid& g = grids[static_cast<std::size_t>(c)];
        const int h = half_window(cls);
        const double floor = params.threshold_scale * cls.threshold;
        // Window sums and their local maxima among the 8 neighbours.
        std::vector<double> s(static_cast<std::size_t>(g.nx) * g.ny);
        for (int x = 0; x < g.nx; ++x) {
            for (int y = 0; y < g.ny; ++y)
                s[static_cast<std::size_t>(x) * g.ny + y] = g.Window(x - h, y - h, x + h, y + h);
        }
        std::vector<std::pair<double, int>> peaks;
        for (int x = 0; x < g.nx; ++x) {
            for (int y = 0; y < g.ny; ++y) {
                const double v = s[static_cast<std::size_t>(x) * g.ny + y];
                if (v <= 1e-9 || v < floor) continue;
                bool peak = true;
                for (int dx = -1; dx <= 1 && peak; ++dx) {
                    for (int dy = -1; dy <= 1 && peak; ++dy) {
                        const int X = x + dx, Y = y + dy;
                        if ((dx == 0 && dy == 0) || X < 0 || Y < 0 || X >= g.nx || Y >= g.ny)
                            continue;
                        const double w = s[static_cast<std::size_t>(X) * g.ny + Y];
                        peak = w < v || (w == v && (X * g.ny + Y) > (x * g.ny + y));
                    }
                }
                if (peak) peaks.push_back({v, x * g.ny + y});
            }
        }
        std::sort(peaks.begin(), peaks.end(), [](const auto& a, const auto& b) {
            return a.first != b.first ? a.first > b.first : a.second < b.second;
        });
        // Maxima in windows of the class width: greedy, strongest first.
        std::vector<Eigen::Vector2i> kept;
        for (const auto& [v, idx] : peaks) {
            const Eigen::Vector2i at(idx / g.ny, idx % g.ny);
            bool free = true;
            for (const auto& k : kept) free = free && (k - at).cwiseAbs().maxCoeff() > h;
            if (!free) continue;
            kept.push_back(at);
            FurnitureHypothesis hyp;
            hyp.cls = c;
            hyp.score = static_cast<float>(v);
            hyp.normalized = cls.threshold > 0.0f ? hyp.score / cls.threshold
                                                  : std::numeric_limits<float>::infinity();
            hyp.found = hyp.normalized;
            // The weighted mean of the window's votes, and the parts they came from.
            const Eigen::Vector2f centre = g.origin + g.cell * at.cast<float>();
            const float half = (static_cast<float>(h) + 0.5f) * g.cell;
            Eigen::Vector2d mean = Eigen::Vector2d::Zero();
            double total = 0.0;
            std::map<std::pair<int, int>, double> support;
            for (const auto* vote : cv) {
                if ((vote->x.head<2>() - centre).cwiseAbs().maxCoeff() > half) continue;
                mean += static_cast<double>(vote->weight) * vote->x.head<2>().cast<double>();
                total += vote->weight;
                support[{vote->view, vote->part}] += vote->weight;
            }
            hyp.centre = total > 0.0 ? (mean / total).cast<float>() : centre;
            double strongest = 0.0;
            for (const auto& [key, w] : support) strongest = std::max(strongest, w);
            std::vector<std::pair<double, std::pair<int, int>>> ordered;
            for (const auto& [key, w] : support) {
                if (w >= params.min_part_share * strongest) ordered.push_back({w, key});
            }
            std::sort(ordered.begin(), ordered.end(), [](const auto& a, const auto& b) {
                return a.first != b.first ? a.first > b.first : a.second < b.second;
            });
            for (const auto& [w, key] : ordered) {
                hyp.parts.push_back(key);
                hyp.part_weights.push_back(static_cast<float>(w * scale));
            }
            out.push_back(std::move(hyp));
        }
    }
    auto by_strength = [](const auto& a, const auto& b) { return a.normalized > b.normalized; };
    std::stable_sort(out.begin(), out.end(), by_strength);
    if (params.hull_consistency) out = Consistent(std::move(out), model, params.cross_class);
    if (!params.other_classes) return out;
    // Every class where a strong hypothesis of another class stands, unless one is near.
    std::vector<FurnitureHypothesis> proposed;
    for (const auto& src : out) {
        if (!(src.normalized >= params.other_classes_from)) continue;
        for (int c = 0; c < n_classes; ++c) {
            if (c == src.cls) continue;
            const FurnitureClass& cls = model.classes()[static_cast<std::size_t>(c)];
            bool near = false;
            for (const auto* list : {&out, &proposed}) {
                for (const auto& k : *list) {
                    near = near || (k.cls == c && (k.centre - src.centre).norm() < cls.width / 2);
                }
            }
            if (near) continue;
            FurnitureHypothesis hyp;
            hyp.cls = c;
            hyp.centre = src.centre;
            const VoteGrid& g = grids[static_cast<std::size_t>(c)];
            if (g.nx > 0) {
                const int h = half_window(cls), x = g.Cx(src.centre.x()), y = g.Cy(src.centre.y());
                hyp.score = static_cast<float>(g.Window(x - h, y - h, x + h, y + h));
            }
            hyp.normalized = cls.threshold > 0.0f ? hyp.score / cls.threshold
                                                  : std::numeric_limits<float>::infinity();
            hyp.parts = src.parts;
            hyp.part_weights = src.part_weights;
            hyp.proposed_by = src.cls;
            hyp.found = src.normalized;
            proposed.push_back(std::move(hyp));
        }
    }
    out.insert(out.end(), std::make_move_iterator(proposed.begin()),
               std::make_move_iterator(proposed.end()));
    std::stable_sort(out.begin(), out.end(), by_strength);
    return out;
}

}  // namespace multicue
