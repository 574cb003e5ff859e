// The task file of `multicue run` (YAML or JSON). It may name a manifest of frames: the input
// itself is there under the names task.yaml and manifest.json, so such a reference reads it again.

#include "fuzz_target.hpp"
#include "task_file.hpp"

MULTICUE_FUZZ_TARGET(task) {
    using namespace multicue;
    const auto bytes = fuzz::Bytes(data, size);
    fuzz::WriteInput(bytes, "manifest.json");
    const auto path = fuzz::WriteInput(bytes, "task.yaml");
    fuzz::AllowTypedErrors([&] { cli::ReadTaskFile(path); });
}
