#pragma once
/// \file Procedural kitchen units: cupboards, sink cupboards, drawer units, wall and tall
/// cupboards built from boards, with doors, drawers, flaps and fixed panels in random layouts,
/// flat or framed fronts, and bar and knob handles of random size and placement; and appliances
/// (dishwashers, ovens, fridges) built the same way.
///
/// PartNet-Mobility holds few designs of each kind (three drawer counters and one oven in the
/// tune half), so classifiers and rules trained or validated on one half of the library meet
/// unit designs on the other half they never saw. Procedural units add as many designs as
/// training wants; they never replace the library's held-out half for evaluation.
///
/// The models follow the conventions of LoadArticulatedModel: z up, fronts facing +x, the closed
/// model's bounding box centred on x = y = 0 with its bottom at z = 0; one root link (semantic
/// "furniture_body") and one link per door ("rotation_door", revolute, opening towards +x) or
/// drawer ("drawer", prismatic along +x, with its box); handles are parts named "handle" and
/// knobs parts named "knob" of their front's link (an oven's or dishwasher's control knobs of the
/// root link); vertex colours and laser reflectances are set.

#include <cstdint>
#include <string>
#include <vector>

#include "multicue/sim/articulated.hpp"
#include "multicue/sim/kitchen_library.hpp"

namespace multicue::sim {

/// The kinds MakeProceduralUnit builds: cupboard, sink_cupboard, drawer_unit, wall_cupboard,
/// tall_cupboard.
const std::vector<std::string>& ProceduralUnitKinds();

/// The appliance kinds MakeProceduralUnit also builds: dishwasher (a flap hinged at its bottom,
/// now and then under a control strip), oven (a flap with a window under a panel of knobs,
/// now and then over a drawer), fridge (one or two doors hinged on one side, tall or under the
/// counter).
const std::vector<std::string>& ProceduralApplianceKinds();

/// A random unit of `kind`, deterministic for a seed; its id is "procedural/<kind>/<seed in hex>".
/// Throws InvalidArgument for a kind in neither ProceduralUnitKinds() nor
/// ProceduralApplianceKinds().
ArticulatedModel MakeProceduralUnit(const std::string& kind, std::uint64_t seed);

/// The most procedural units of a kind a library may list (each is built when a kitchen of the
/// library is made).
inline constexpr int kMaxProceduralPerKind = 1000;

/// `per_kind` library entries of every procedural cupboard kind, and with `appliances` of every
/// appliance kind too (KitchenModelEntry::procedural set, ids "procedural/<kind>/<its seed in
/// hex>"), their seeds drawn from `seed` (a cupboard kind's are the same either way).
/// KitchenModelCache builds them on first use. Throws InvalidArgument for a count outside
/// [0, kMaxProceduralPerKind].
std::vector<KitchenModelEntry> ProceduralKitchenEntries(int per_kind, std::uint64_t seed,
                                                        bool appliances = false);

}  // namespace multicue::sim
