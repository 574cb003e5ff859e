// Classifier specs as the command line and model files give them ("knn:k=5,metric=l1").

#include <string>

#include "fuzz_target.hpp"
#include "multicue/ml/classifier.hpp"

MULTICUE_FUZZ_TARGET(classifier_spec) {
    using namespace multicue;
    const std::string spec(fuzz::Bytes(data, size));
    fuzz::AllowTypedErrors([&] {
        const auto c = ml::CreateClassifier(spec);
        // A spec that was accepted describes itself as one that is accepted again.
        ml::CreateClassifier(c->spec());
    });
}
