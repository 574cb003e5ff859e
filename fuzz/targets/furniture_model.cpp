// Furniture models (vocabulary, shape models and CAD models of `multicue map furniture`'s
// training).

#include "multicue/recognition/furniture_model.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(furniture_model) {
    using namespace multicue;
    const auto path = fuzz::WriteContainerInput(fuzz::Bytes(data, size), "MCFURNIT",
                                                FurnitureModel::kFormatVersion, "input.mcfm");
    fuzz::AllowTypedErrors([&] { FurnitureModel::Load(path); });
}
