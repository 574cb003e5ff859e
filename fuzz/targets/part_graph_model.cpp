// Part-graph hashing models (.mcpg, `multicue train`).

#include "multicue/recognition/part_graph_model.hpp"
#include "fuzz_target.hpp"

MULTICUE_FUZZ_TARGET(part_graph_model) {
    using namespace multicue;
    const auto path = fuzz::WriteContainerInput(fuzz::Bytes(data, size), "MCPARTGR",
                                                kPartGraphModelVersion, "input.mcpg");
    fuzz::AllowTypedErrors([&] { PartGraphModel::Load(path); });
}
