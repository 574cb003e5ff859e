// The parameter file of `multicue perceive --config` (JSON with comments), checked as
// `multicue config --check` does.

#include "fuzz_target.hpp"
#include "multicue/io/config.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_report.hpp"

MULTICUE_FUZZ_TARGET(perceive_config) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "config.json");
    fuzz::AllowTypedErrors([&] {
        auto config = io::ConfigSection::Load(path);
        PerceiveParams params;
        ReportParams report;
        ReadPerceiveParams(config, params);
        ReadReportParams(config, report);
        config.CheckAllUsed();
        params.Validate();
    });
}
