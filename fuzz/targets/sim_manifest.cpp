// The manifest.json of `multicue simulate` as `perceive --manifest` and `run` read it.

#include "sim_manifest.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(sim_manifest) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "manifest.json");
    fuzz::AllowTypedErrors([&] { cli::ReadSimManifest(path); });
}
