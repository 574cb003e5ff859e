#include "multicue/system/executive_json.hpp"

namespace multicue {

Task TaskFromJson(const nlohmann::json& j, const std::string& where) {
    Task task;
    try {
        task.kind = ParseTaskKind(j.value("task", std::string("enumerate")));
        if (j.contains("target")) {
            task.target =
                j["target"].is_string() ? j["target"].get<std::string>() : j["target"].dump();
        }
        task.learn = j.value("learn", true);
        for (const auto& name : j.value("possible_objects", nlohmann::json::array())) {
            task.possible_objects.push_back(name.is_string() ? name.get<std::string>()
                                                             : name.dump());
        }
        if (j.contains("region")) {
            const auto& r = j["region"];
            for (const auto& [key, value] : r.items()) {
                if (key != "min" && key != "max")
                    throw InvalidArgument(where + " region: unknown key '" + key + "'");
            }
            const auto lo = r.at("min").get<std::vector<double>>();
            const auto hi = r.at("max").get<std::vector<double>>();
            if (lo.size() != 3 || hi.size() != 3)
                throw InvalidArgument(where + ": region min/max need 3 numbers");
            task.region = Eigen::AlignedBox3d(Eigen::Vector3d(lo[0], lo[1], lo[2]),
                                              Eigen::Vector3d(hi[0], hi[1], hi[2]));
        }
    } catch (const nlohmann::json::exception& e) {
        throw InvalidArgument(where + ": " + e.what());
    }
    return task;
}

nlohmann::ordered_json HypothesisJson(const Hypothesis& h, const ObjectDatabase* db) {
    nlohmann::ordered_json j;
    j["id"] = h.id;
    j["object_id"] = h.object_id;
    if (db != nullptr && h.object_id > 0) {
        if (const auto o = db->GetObject(h.object_id)) j["object"] = o->name;
    }
    j["novel"] = h.novel;
    j["by_position"] = h.by_position;
    j["category"] = h.Category();
    j["categories"] = h.categories;
    nlohmann::ordered_json identities = nlohmann::ordered_json::object();
    for (const auto& [id, p] : h.identities) identities[std::to_string(id)] = p;
    j["identities"] = identities;
    j["position"] = {h.position.x(), h.position.y(), h.position.z()};
    j["extents"] = {h.extents.x(), h.extents.y(), h.extents.z()};
    j["points"] = h.indices.size();
    j["model"] = h.model;
    j["provenance"] = h.provenance;
    return j;
}

nlohmann::ordered_json FrameReportJson(const FrameReport& report, const Task& task,
                                       const ObjectDatabase* db) {
    nlohmann::ordered_json jf;
    jf["frame"] = report.frame;
    jf["time"] = report.time;
    jf["methods"] = report.methods;
    jf["learnt_objects"] = report.learnt_objects;
    jf["learnt_views"] = report.learnt_views;
    if (task.kind == Task::Kind::kFind) {
        jf["found"] = report.found ? nlohmann::ordered_json(report.hypotheses[*report.found].id)
                                   : nlohmann::ordered_json(nullptr);
    }
    nlohmann::ordered_json hyps = nlohmann::ordered_json::array();
    for (const auto& h : report.hypotheses) hyps.push_back(HypothesisJson(h, db));
    jf["hypotheses"] = hyps;
    nlohmann::ordered_json timings = nlohmann::ordered_json::object();
    for (const auto& [stage, ms] : report.timings_ms) timings[stage] = ms;
    jf["timings_ms"] = timings;
    return jf;
}

}  // namespace multicue
