#pragma once
/// \file Tasks and frame reports of the perception executive as JSON: what `multicue run` writes
/// per frame and what the ROS node's task service takes and returns.

#include <string>

#include <nlohmann/json.hpp>

#include "multicue/system/executive.hpp"

namespace multicue {

/// A task from its keys: "task" (enumerate, find or model; default enumerate), "target",
/// "learn" (default true), "possible_objects" (list), "region" ({"min": [x,y,z], "max": [x,y,z]}).
/// Other keys are left for the caller. Throws InvalidArgument naming `where` for a bad value.
Task TaskFromJson(const nlohmann::json& spec, const std::string& where);

/// One hypothesis: ids, object name (when the database knows it), category distribution,
/// identities, position, extents, points, model and provenance.
nlohmann::ordered_json HypothesisJson(const Hypothesis& hypothesis, const ObjectDatabase* db);

/// One frame's report: frame, time, methods, learnt objects and views, "found" for kFind, the
/// hypotheses and the timings.
nlohmann::ordered_json FrameReportJson(const FrameReport& report, const Task& task,
                                       const ObjectDatabase* db);

}  // namespace multicue
