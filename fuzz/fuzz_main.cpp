// The libFuzzer entry points of a fuzz_<name> program: exactly one target is linked in.

#include <cstdio>
#include <cstdlib>

#include "fuzz_target.hpp"
#include "multicue/core/logging.hpp"

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
    if (multicue::fuzz::Targets().size() != 1) {
        std::fprintf(stderr, "a fuzz program needs exactly one target, got %zu\n",
                     multicue::fuzz::Targets().size());
        std::abort();
    }
    // Messages are formatted (that code runs too) but not printed.
    multicue::SetLogSink([](multicue::LogLevel, std::string_view) {});
    multicue::SetLogLevel(multicue::LogLevel::kDebug);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const multicue::fuzz::Entry entry = multicue::fuzz::Targets().begin()->second;
    entry(data, size);
    return 0;
}
