// Classifier model files (k-NN, SVM, boosting, MLP, random forests; format versions 1 and 2): a
// model that loads must also predict.

#include "multicue/ml/classifier.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(classifier) {
    using namespace multicue;
    for (const std::uint32_t version : {ml::kModelFormatVersion, 1u}) {
        const auto path =
            fuzz::WriteContainerInput(fuzz::Bytes(data, size), "MCUEMODL", version, "input.mcm");
        fuzz::AllowTypedErrors([&] {
            const auto c = ml::LoadClassifier(path);
            const ml::FeatureMatrix x =
                ml::FeatureMatrix::Zero(2, static_cast<Eigen::Index>(c->num_features()));
            const ml::FeatureMatrix p = c->PredictProba(x);
            if (p.rows() != 2 || p.cols() != static_cast<Eigen::Index>(c->num_classes())) {
                throw std::logic_error("classifier: confidences of the wrong shape");
            }
        });
    }
}
