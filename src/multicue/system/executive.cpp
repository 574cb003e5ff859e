#include "multicue/system/executive.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/features/colour.hpp"

namespace multicue {
namespace {

using Clock = std::chrono::steady_clock;

double Milliseconds(Clock::time_point since) {
    return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

constexpr const char* kColour = "colour";
constexpr const char* kShape = "shape";

// ---------------------------------------------------------------------------------------------
// Segmentation: the table-top pipeline turns a frame into object hypotheses.

class SegmentationMethod final : public ExaminationMethod {
  public:
    std::string Name() const override { return "segmentation"; }
    std::vector<std::string> Requires() const override { return {}; }
    std::vector<std::string> Provides() const override {
        return {"hypotheses", "category", "model"};
    }

    void Examine(ExaminationContext& context, std::vector<Hypothesis>& hypotheses) override {
        const PointCloud& cloud = context.frame.cloud;
        context.perceive = Perceive(cloud, context.params.perceive,
                                    context.models ? *context.models : PerceiveModels{});
        const Eigen::Isometry3d& T = context.frame.T_world_sensor;
        for (const auto& object : context.perceive->objects) {
            Hypothesis h;
            h.id = object.id;
            h.indices = object.indices;
            // The model's centre moves less between viewpoints than the centroid of the seen side.
            Eigen::Vector3f center = object.centroid;
            if (object.model.box && object.model.box->found) {
                center = object.model.box->center;
            } else if (object.model.cylinder && object.model.cylinder->found) {
                center = object.model.cylinder->center;
            }
            h.position = T * center.cast<double>();
            h.extents = Extents(cloud, object);
            for (std::size_t c = 1; c < kNumCategories; ++c) {
                const float p = object.category.probabilities[c];
                if (p > 0.0f) h.categories[std::string(kCategoryNames[c])] = p;
            }
            h.model = ModelJson(object.model);
            h.provenance.push_back(Name());
            hypotheses.push_back(std::move(h));
        }
    }

  private:
    static Eigen::Vector3f Extents(const PointCloud& cloud, const PerceivedObject& object) {
        Eigen::Vector3f e = Eigen::Vector3f::Zero();
        if (object.model.box && object.model.box->found) {
            e = object.model.box->extents;
        } else if (object.model.cylinder && object.model.cylinder->found) {
            const auto& c = *object.model.cylinder;
            e = {2.0f * c.radius, 2.0f * c.radius, c.height};
        } else if (!object.indices.empty()) {
            Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
            Eigen::Vector3f hi = -lo;
            for (auto i : object.indices) {
                lo = lo.cwiseMin(cloud.points[i]);
                hi = hi.cwiseMax(cloud.points[i]);
            }
            e = hi - lo;
        }
        std::sort(e.data(), e.data() + 3, std::greater<float>());
        return e;
    }

    static nlohmann::json ModelJson(const ObjectModel& model) {
        if (model.box && model.box->found) {
            const auto& b = *model.box;
            return {{"type", "box"},
                    {"extents", {b.extents.x(), b.extents.y(), b.extents.z()}},
                    {"inlier_ratio", b.inlier_ratio}};
        }
        if (model.cylinder && model.cylinder->found) {
            const auto& c = *model.cylinder;
            return {{"type", "cylinder"},
                    {"radius", c.radius},
                    {"height", c.height},
                    {"inlier_ratio", c.inlier_ratio}};
        }
        return nlohmann::json::object();
    }
};

// ---------------------------------------------------------------------------------------------
// Descriptors for identification.

class ColourDescriptorMethod final : public ExaminationMethod {
  public:
    std::string Name() const override { return "colour"; }
    std::vector<std::string> Requires() const override { return {"hypotheses"}; }
    std::vector<std::string> Provides() const override { return {"descriptor:colour"}; }

    /// Hue histogram of saturated points plus a brightness histogram of grey points, sum 1:
    /// stable under the shading changes between viewpoints.
    void Examine(ExaminationContext& context, std::vector<Hypothesis>& hypotheses) override {
        const PointCloud& cloud = context.frame.cloud;
        const int hue_bins = std::max(2, context.params.colour_bins) * 3 / 2;
        const int grey_bins = std::max(2, context.params.colour_bins / 2);
        for (auto& h : hypotheses) {
            std::vector<float> histogram(static_cast<std::size_t>(hue_bins + grey_bins), 0.0f);
            if (cloud.HasColors()) {
                for (auto i : h.indices) {
                    // Hue in degrees, saturation and value in [0, 1].
                    const Eigen::Vector3f hsv = RgbToHsv(cloud.colors[i]);
                    const float mx = hsv[2];
                    if (hsv[1] > 0.25f && mx > 0.1f) {
                        const int bin =
                            std::min(hue_bins - 1, static_cast<int>(hsv[0] / 360.0f * hue_bins));
                        histogram[static_cast<std::size_t>(bin)] += 1.0f;
                    } else {
                        const int bin = std::min(grey_bins - 1, static_cast<int>(mx * grey_bins));
                        histogram[static_cast<std::size_t>(hue_bins + bin)] += 1.0f;
                    }
                }
            }
            float sum = 0.0f;
            for (float v : histogram) sum += v;
            if (sum > 0.0f) {
                for (float& v : histogram) v /= sum;
            }
            h.descriptors[kColour] = std::move(histogram);
            h.provenance.push_back(Name());
        }
    }
};

class ShapeDescriptorMethod final : public ExaminationMethod {
  public:
    std::string Name() const override { return "shape"; }
    std::vector<std::string> Requires() const override { return {"hypotheses", "category"}; }
    std::vector<std::string> Provides() const override { return {"descriptor:shape"}; }

    /// Sorted extents [m] followed by the category distribution (contract order, "none" left out).
    void Examine(ExaminationContext&, std::vector<Hypothesis>& hypotheses) override {
        for (auto& h : hypotheses) {
            std::vector<float> d{h.extents.x(), h.extents.y(), h.extents.z()};
            for (std::size_t c = 1; c < kNumCategories; ++c) {
                const auto it = h.categories.find(std::string(kCategoryNames[c]));
                d.push_back(it == h.categories.end() ? 0.0f : static_cast<float>(it->second));
            }
            h.descriptors[kShape] = std::move(d);
            h.provenance.push_back(Name());
        }
    }
};

// ---------------------------------------------------------------------------------------------
// Identification against the object model database.

struct Candidate {
    ObjectRecord object;
    std::vector<ObjectView> views;
};

/// Smallest distance between a descriptor and any stored view's descriptor of the same kind;
/// NaN when no view has that kind.
double NearestViewDistance(const Candidate& candidate, const std::string& kind,
                           const std::vector<float>& descriptor) {
    double best = std::numeric_limits<double>::quiet_NaN();
    for (const auto& view : candidate.views) {
        const auto it = view.descriptors.find(kind);
        if (it == view.descriptors.end() || it->second.size() != descriptor.size()) continue;
        const double d = DescriptorDistance(kind, descriptor, it->second);
        if (!(d >= best)) best = d;
    }
    return best;
}

class IdentificationMethod final : public ExaminationMethod {
  public:
    std::string Name() const override { return "identification"; }
    std::vector<std::string> Requires() const override { return {"hypotheses", "descriptor"}; }
    std::vector<std::string> Provides() const override { return {"identity"}; }

    void Examine(ExaminationContext& context, std::vector<Hypothesis>& hypotheses) override {
        std::vector<Candidate> candidates;
        if (context.database != nullptr) {
            for (auto& o : context.database->ListObjects()) {
                if (!Admissible(context.task, o)) continue;
                Candidate c{o, context.database->GetViews(o.id)};
                candidates.push_back(std::move(c));
            }
        }
        for (auto& h : hypotheses) {
            h.provenance.push_back(Name());
            Identify(context, candidates, h);
        }
    }

  private:
    static bool Admissible(const Task& task, const ObjectRecord& o) {
        auto matches = [&](const std::string& name) {
            return name == o.name || name == std::to_string(o.id);
        };
        if (!task.possible_objects.empty() &&
            std::none_of(task.possible_objects.begin(), task.possible_objects.end(), matches)) {
            return false;
        }
        if (task.kind == Task::Kind::kFind) return matches(task.target);
        return true;
    }

    static void Identify(const ExaminationContext& context,
                         const std::vector<Candidate>& candidates, Hypothesis& h) {
        const auto& params = context.params;
        if (candidates.empty()) {
            h.novel = true;
            return;
        }
        // Distances per descriptor kind and candidate.
        std::vector<std::string> kinds;
        for (const auto& [kind, value] : h.descriptors) kinds.push_back(kind);
        std::vector<std::vector<double>> distance(
            candidates.size(),
            std::vector<double>(kinds.size(), std::numeric_limits<double>::quiet_NaN()));
        for (std::size_t c = 0; c < candidates.size(); ++c) {
            for (std::size_t k = 0; k < kinds.size(); ++k) {
                distance[c][k] =
                    NearestViewDistance(candidates[c], kinds[k], h.descriptors.at(kinds[k]));
            }
        }
        // The worst agreement over the descriptor kinds: one kind that clearly disagrees is enough
        // to call the object another one.
        auto worst_distance = [&](std::size_t c) {
            double worst = -1.0;
            for (double d : distance[c]) {
                if (!std::isnan(d)) worst = std::max(worst, d);
            }
            return worst < 0.0 ? std::numeric_limits<double>::infinity() : worst;
        };
        // Identity by position: a known object last seen at this place (section 3.2.4), unless its
        // descriptors say it is clearly something else (the object was replaced).
        double nearest = std::numeric_limits<double>::max();
        std::size_t here = candidates.size();
        for (std::size_t c = 0; c < candidates.size(); ++c) {
            const double d = (candidates[c].object.last_pose.block<3, 1>(0, 3) - h.position).norm();
            if (d < nearest) {
                nearest = d;
                here = c;
            }
        }
        if (here < candidates.size() && nearest <= params.same_place_radius &&
            worst_distance(here) <= 2.0 * params.novelty_distance) {
            h.identities = {{candidates[here].object.id, 1.0}};
            h.object_id = candidates[here].object.id;
            h.by_position = true;
            return;
        }
        std::vector<std::size_t> alive(candidates.size());
        for (std::size_t c = 0; c < alive.size(); ++c) alive[c] = c;
        if (!params.parallel_merge) {
            // Hierarchic filtering: each descriptor in turn removes the identities it rules out.
            for (std::size_t k = 0; k < kinds.size() && !alive.empty(); ++k) {
                std::erase_if(alive, [&](std::size_t c) {
                    return !std::isnan(distance[c][k]) && distance[c][k] > params.novelty_distance;
                });
            }
        }
        // Identity distribution: product over kinds of exp(-d / s), normalised.
        constexpr double kScale = 0.1;
        std::vector<double> score(candidates.size(), 0.0);
        double total = 0.0;
        for (std::size_t c : alive) {
            double log_score = 0.0;
            for (double d : distance[c]) {
                if (!std::isnan(d)) log_score -= d / kScale;
            }
            score[c] = std::exp(log_score);
            total += score[c];
        }
        std::size_t best = candidates.size();
        double best_distance = std::numeric_limits<double>::infinity();
        for (std::size_t c : alive) {
            if (total > 0.0) h.identities[candidates[c].object.id] = score[c] / total;
            const double d = worst_distance(c);
            if (best == candidates.size() || score[c] > score[best] ||
                (score[c] == score[best] && d < best_distance)) {
                best = c;
                best_distance = d;
            }
        }
        if (best == candidates.size() || best_distance > params.novelty_distance) {
            h.novel = true;
            return;
        }
        h.object_id = candidates[best].object.id;
    }
};

/// The descriptor kinds that tell the sought object apart from every other known object, best
/// first: the distance from the target's views to the nearest other object's view, per kind.
std::vector<std::string> SingleOutDescriptors(const ObjectDatabase& database, const Task& task,
                                              double novelty_distance) {
    std::vector<Candidate> all;
    const Candidate* target = nullptr;
    for (auto& o : database.ListObjects()) all.push_back({o, database.GetViews(o.id)});
    for (const auto& c : all) {
        if (c.object.name == task.target || std::to_string(c.object.id) == task.target) target = &c;
    }
    if (target == nullptr) return {};
    std::map<std::string, double> separation;
    for (const auto& view : target->views) {
        for (const auto& [kind, descriptor] : view.descriptors) {
            double nearest_other = std::numeric_limits<double>::infinity();
            for (const auto& other : all) {
                if (&other == target) continue;
                const double d = NearestViewDistance(other, kind, descriptor);
                if (!std::isnan(d)) nearest_other = std::min(nearest_other, d);
            }
            auto [it, inserted] = separation.emplace(kind, nearest_other);
            if (!inserted) it->second = std::min(it->second, nearest_other);
        }
    }
    std::vector<std::pair<double, std::string>> ranked;
    for (const auto& [kind, d] : separation) ranked.emplace_back(d, kind);
    std::sort(ranked.rbegin(), ranked.rend());
    // One kind suffices when it alone keeps every other object beyond the novelty distance.
    if (!ranked.empty() && ranked.front().first > novelty_distance) return {ranked.front().second};
    std::vector<std::string> kinds;
    for (const auto& [d, kind] : ranked) kinds.push_back(kind);
    return kinds;
}

/// A copy of the frame with every point outside the world-frame box set to NaN (organization kept).
Frame RestrictToRegion(const Frame& frame, const Eigen::AlignedBox3d& region) {
    Frame restricted = frame;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    auto& points = restricted.cloud.points;
    for (auto& p : points) {
        if (!p.allFinite()) continue;
        if (!region.contains(frame.T_world_sensor * p.cast<double>())) p.setConstant(nan);
    }
    if (restricted.cloud.HasNormals()) restricted.cloud.normals.clear();
    return restricted;
}

/// Runs the planned methods in order on one input frame (section 3.1.3: each refines the
/// hypotheses of the ones before). Right after segmentation the task narrows the hypotheses: to
/// its region, and for a model task without a database to the target category. Appends each
/// method's time to the report.
std::vector<Hypothesis> ExamineFrame(const Frame& input, const Task& task,
                                     const ExecutiveParams& params, const ObjectDatabase* database,
                                     const PerceiveModels& models,
                                     const std::vector<std::unique_ptr<ExaminationMethod>>& methods,
                                     FrameReport& report) {
    ExaminationContext context{input, task, params, database, &models, std::nullopt};
    std::vector<Hypothesis> hypotheses;
    for (const auto& name : report.methods) {
        const auto start = Clock::now();
        for (const auto& m : methods) {
            if (m->Name() != name) continue;
            m->Examine(context, hypotheses);
            if (name == "segmentation" && task.region) {
                std::erase_if(hypotheses, [&](const Hypothesis& h) {
                    return !task.region->contains(h.position);
                });
            }
            if (name == "segmentation" && task.kind == Task::Kind::kModel && !task.target.empty() &&
                database == nullptr) {
                std::erase_if(hypotheses,
                              [&](const Hypothesis& h) { return h.Category() != task.target; });
            }
        }
        report.timings_ms.emplace_back(name, Milliseconds(start));
    }
    return hypotheses;
}

/// The database's record of a find task's target (the last one listed of that name or id).
std::optional<ObjectRecord> SoughtObject(const ObjectDatabase* database, const Task& task) {
    std::optional<ObjectRecord> sought;
    if (task.kind == Task::Kind::kFind && database != nullptr) {
        for (auto& o : database->ListObjects()) {
            if (o.name == task.target || std::to_string(o.id) == task.target) sought = o;
        }
    }
    return sought;
}

/// The column of world space within `margin` of where the object was last seen, at any height.
Eigen::AlignedBox3d NearLastPlace(const ObjectRecord& sought, double margin) {
    const Eigen::Vector3d p = sought.last_pose.block<3, 1>(0, 3);
    const double m = margin;
    const double inf = std::numeric_limits<double>::max();
    return Eigen::AlignedBox3d(Eigen::Vector3d(p.x() - m, p.y() - m, -inf),
                               Eigen::Vector3d(p.x() + m, p.y() + m, inf));
}

/// Sets report.found to the (last) hypothesis identified as the sought object, if any.
void LocateSought(const std::optional<ObjectRecord>& sought, FrameReport& report) {
    report.found.reset();
    for (std::size_t i = 0; i < report.hypotheses.size(); ++i) {
        const auto& h = report.hypotheses[i];
        if (sought && h.object_id == sought->id) report.found = i;
    }
}

/// What the database learns from one hypothesis (section 3.2.4): a novel object with its first
/// view (not during a search: it learns no strangers), a new view of a known object when it
/// differs from every stored one, else only where the object was seen.
void LearnFromHypothesis(ObjectDatabase& database, const Task& task, const Frame& frame,
                         double new_view_distance, Hypothesis& h, FrameReport& report) {
    Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
    pose.block<3, 1>(0, 3) = h.position;
    ObjectView view;
    view.time = frame.time;
    view.frame = frame.name;
    view.category = h.Category();
    view.category_probabilities = h.categories;
    view.descriptors = h.descriptors;
    view.model = h.model;
    view.pose = pose;
    if (h.novel) {
        if (task.kind == Task::Kind::kFind) return;  // a search learns no strangers
        ObjectRecord object;
        object.category = view.category;
        object.created = frame.time;
        object.last_seen = frame.time;
        object.last_pose = pose;
        h.object_id = database.AddObjectWithView(object, view);
        ++report.learnt_objects;
        return;
    }
    if (h.object_id == 0) return;
    // A new view when it differs from every stored view of the object.
    Candidate known{*database.GetObject(h.object_id), database.GetViews(h.object_id)};
    double nearest = 0.0;
    for (const auto& [kind, descriptor] : h.descriptors) {
        const double d = NearestViewDistance(known, kind, descriptor);
        if (!std::isnan(d)) nearest = std::max(nearest, d);
    }
    if (nearest >= new_view_distance) {
        view.object_id = h.object_id;
        database.AddView(view);
        ++report.learnt_views;
    } else {
        database.UpdateLastSeen(h.object_id, frame.time, pose);
    }
}

}  // namespace

std::string Hypothesis::Category() const {
    std::string best;
    double p_best = 0.0;
    for (const auto& [name, p] : categories) {
        if (p > p_best) {
            p_best = p;
            best = name;
        }
    }
    return best;
}

Task::Kind ParseTaskKind(const std::string& name) {
    if (name == "enumerate") return Task::Kind::kEnumerate;
    if (name == "find") return Task::Kind::kFind;
    if (name == "model") return Task::Kind::kModel;
    throw InvalidArgument("unknown task '" + name + "' (expected enumerate, find or model)");
}

double DescriptorDistance(const std::string& kind, const std::vector<float>& a,
                          const std::vector<float>& b) {
    if (a.size() != b.size()) {
        throw InvalidArgument("descriptor '" + kind + "': sizes differ (" +
                              std::to_string(a.size()) + " vs " + std::to_string(b.size()) + ")");
    }
    if (kind == kShape && a.size() >= 3) {
        // Relative extent differences and the total variation between category distributions.
        double extent = 0.0;
        for (std::size_t i = 0; i < 3; ++i) {
            const double m = std::max({std::abs(a[i]), std::abs(b[i]), 1e-6f});
            extent += std::min(1.0, std::abs(a[i] - b[i]) / m);
        }
        double category = 0.0;
        for (std::size_t i = 3; i < a.size(); ++i) category += std::abs(a[i] - b[i]);
        return 0.5 * extent / 3.0 + 0.5 * std::min(1.0, 0.5 * category);
    }
    // Histograms (sum 1): chi-square distance, in [0, 1].
    double chi2 = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const double s = static_cast<double>(a[i]) + b[i];
        if (s > 0.0) chi2 += (a[i] - b[i]) * (a[i] - b[i]) / s;
    }
    return std::min(1.0, 0.5 * chi2);
}

std::unique_ptr<ExaminationMethod> MakeSegmentationMethod() {
    return std::make_unique<SegmentationMethod>();
}
std::unique_ptr<ExaminationMethod> MakeColourDescriptorMethod() {
    return std::make_unique<ColourDescriptorMethod>();
}
std::unique_ptr<ExaminationMethod> MakeShapeDescriptorMethod() {
    return std::make_unique<ShapeDescriptorMethod>();
}
std::unique_ptr<ExaminationMethod> MakeIdentificationMethod() {
    return std::make_unique<IdentificationMethod>();
}

PerceptionExecutive::PerceptionExecutive(ObjectDatabase* database, ExecutiveParams params,
                                         PerceiveModels models)
    : database_(database), params_(std::move(params)), models_(std::move(models)) {
    params_.perceive.Validate();
    CheckCategorizationModel(params_.perceive.category, models_.part_graph.get());
    methods_.push_back(MakeSegmentationMethod());
    methods_.push_back(MakeColourDescriptorMethod());
    methods_.push_back(MakeShapeDescriptorMethod());
    methods_.push_back(MakeIdentificationMethod());
}

void PerceptionExecutive::AddMethod(std::unique_ptr<ExaminationMethod> method) {
    if (!method) throw InvalidArgument("executive: null examination method");
    for (const auto& m : methods_) {
        if (m->Name() == method->Name()) {
            throw InvalidArgument("executive: a method named '" + method->Name() + "' exists");
        }
    }
    methods_.push_back(std::move(method));
}

std::vector<std::string> PerceptionExecutive::Plan(const Task& task) const {
    // What the task needs; "descriptor" is met by any descriptor method.
    std::set<std::string> needed = {"hypotheses"};
    if (task.kind == Task::Kind::kModel) needed.insert("model");
    if (task.kind != Task::Kind::kModel || !task.target.empty()) needed.insert("identity");

    std::set<std::string> descriptor_kinds;  // empty = all
    if (task.kind == Task::Kind::kFind && database_ != nullptr) {
        for (const auto& kind : SingleOutDescriptors(*database_, task, params_.novelty_distance)) {
            descriptor_kinds.insert(kind);
        }
    }
    auto wanted_descriptor = [&](const std::string& capability) {
        return descriptor_kinds.empty() ||
               descriptor_kinds.count(capability.substr(std::string("descriptor:").size())) > 0;
    };

    std::vector<std::string> order;
    std::set<std::string> provided;
    std::set<const ExaminationMethod*> chosen;
    // Repeatedly run a method whose requirements are met and that provides something needed.
    for (bool progress = true; progress;) {
        progress = false;
        for (const auto& m : methods_) {
            if (chosen.count(m.get()) > 0) continue;
            bool ready = true;
            for (const auto& r : m->Requires()) {
                if (r == "descriptor") {
                    ready =
                        ready && std::any_of(provided.begin(), provided.end(), [](const auto& p) {
                            return p.rfind("descriptor:", 0) == 0;
                        });
                } else {
                    ready = ready && provided.count(r) > 0;
                }
            }
            if (!ready) continue;
            bool useful = false;
            for (const auto& p : m->Provides()) {
                if (p.rfind("descriptor:", 0) == 0) {
                    useful = useful || (needed.count("identity") > 0 && wanted_descriptor(p));
                } else {
                    useful = useful || needed.count(p) > 0 ||
                             (p == "category" && needed.count("identity") > 0);
                }
            }
            if (!useful) continue;
            chosen.insert(m.get());
            order.push_back(m->Name());
            for (const auto& p : m->Provides()) provided.insert(p);
            progress = true;
        }
    }
    for (const auto& n : needed) {
        if (provided.count(n) == 0) {
            throw InvalidArgument("executive: no examination method provides '" + n + "'");
        }
    }
    return order;
}

FrameReport PerceptionExecutive::Run(const Frame& frame, const Task& task) {
    if (task.kind == Task::Kind::kFind && task.target.empty()) {
        throw InvalidArgument("task find: no target object given");
    }
    FrameReport report;
    report.frame = frame.name;
    report.time = frame.time;
    report.methods = Plan(task);
    auto examine = [&](const Frame& input) {
        return ExamineFrame(input, task, params_, database_, models_, methods_, report);
    };

    // Active search: look where the sought object was last seen first (a prior from the task).
    const std::optional<ObjectRecord> sought = SoughtObject(database_, task);
    bool searched_whole_frame = true;
    if (sought && !task.region) {
        report.hypotheses =
            examine(RestrictToRegion(frame, NearLastPlace(*sought, params_.search_margin)));
        searched_whole_frame = false;
    } else {
        report.hypotheses = examine(frame);
    }
    LocateSought(sought, report);
    if (!report.found && !searched_whole_frame) {
        LogInfo("active search: {} not near its last place; searching the whole frame",
                task.target);
        report.hypotheses = examine(frame);
        LocateSought(sought, report);
    }

    // Learning (section 3.2.4): novel objects, new views, and where everything was seen.
    if (database_ != nullptr && task.learn) {
        const auto start = Clock::now();
        for (auto& h : report.hypotheses) {
            LearnFromHypothesis(*database_, task, frame, params_.new_view_distance, h, report);
        }
        report.timings_ms.emplace_back("learning", Milliseconds(start));
    }
    return report;
}

}  // namespace multicue
