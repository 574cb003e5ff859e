// Feature transforms (min-max, z-score, PCA): a transform that loads must also apply.

#include "multicue/ml/transform.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(transform) {
    using namespace multicue;
    const auto path = fuzz::WriteContainerInput(fuzz::Bytes(data, size), "MCUEXFRM",
                                                ml::kTransformFormatVersion, "input.mcx");
    fuzz::AllowTypedErrors([&] {
        const ml::FeatureTransform t = ml::LoadTransform(path);
        const ml::FeatureMatrix x =
            ml::FeatureMatrix::Zero(2, static_cast<Eigen::Index>(t.input_dims()));
        t.Apply(x);
    });
}
