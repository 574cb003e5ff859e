// The manifest.json of `multicue simulate` as `multicue dataset extract --manifest` reads it
// (objects with labels and categories, frames with poses).

#include "fuzz_target.hpp"
#include "multicue/recognition/dataset_extraction.hpp"

MULTICUE_FUZZ_TARGET(dataset_manifest) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "manifest.json");
    fuzz::AllowTypedErrors([&] { ManifestInputs(path); });
}
