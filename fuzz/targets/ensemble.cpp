// Ensemble files (members, rule, weights, level-1 classifier).

#include "multicue/ml/ensemble.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(ensemble) {
    using namespace multicue;
    const auto path = fuzz::WriteContainerInput(fuzz::Bytes(data, size), "MCUEENSM",
                                                ml::kEnsembleFormatVersion, "input.mce");
    fuzz::AllowTypedErrors([&] { ml::Ensemble::Load(path); });
}
