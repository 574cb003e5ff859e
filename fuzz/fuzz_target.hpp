#pragma once
// One fuzz target per reader. A target is a function of the input bytes that calls the reader the
// way the CLI does; it lets multicue's typed errors (multicue::Error) pass, since refusing bad
// input is the reader's job, and lets everything else through: a crash, a sanitizer report, a
// hang or any other exception (std::bad_alloc, a JSON library's exception, ...) is a bug.
//
// A target file defines its function with MULTICUE_FUZZ_TARGET(name). The same file is built
// into a libFuzzer program (fuzz_<name>, clang, -DMULTICUE_BUILD_FUZZERS=ON) and into the
// regression test (test_fuzz_regression, any compiler), which replays fuzz/regression/<name>/.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>

#include "multicue/core/exceptions.hpp"

namespace multicue::fuzz {

using Entry = void (*)(const std::uint8_t* data, std::size_t size);

/// Every target linked into this program, by name.
std::map<std::string, Entry>& Targets();

struct Registration {
    Registration(const char* name, Entry entry) { Targets()[name] = entry; }
};

/// The bytes as a string_view.
inline std::string_view Bytes(const std::uint8_t* data, std::size_t size) {
    return {reinterpret_cast<const char*>(data), size};
}

/// Writes the bytes to a file named `name` (with the extension the reader expects) in a folder of
/// this process, replacing the previous input, and returns its path. The readers take paths, so
/// the file system is part of what is fuzzed, as it is in the CLI.
std::filesystem::path WriteInput(std::string_view bytes, const std::string& name);

/// Writes the bytes as the payload of a container file (ml/serialization.hpp: magic, version,
/// size, checksum), so that the fuzzer reaches the payload decoder instead of stopping at the
/// checksum. Bytes that begin with `magic` are written as they are, so the header is fuzzed too.
std::filesystem::path WriteContainerInput(std::string_view bytes, std::string_view magic,
                                          std::uint32_t version, const std::string& name);

/// Runs `body`, letting multicue::Error pass (the reader refused the input with a message).
template <typename Body>
void AllowTypedErrors(Body&& body) {
    try {
        body();
    } catch (const Error&) {
    }
}

}  // namespace multicue::fuzz

/// Defines fuzz target `name`: `MULTICUE_FUZZ_TARGET(pcd) { ... data, size ... }`.
#define MULTICUE_FUZZ_TARGET(name)                                                 \
    static void MulticueFuzz_##name(const std::uint8_t* data, std::size_t size);   \
    static const ::multicue::fuzz::Registration multicue_fuzz_registration_##name( \
        #name, &MulticueFuzz_##name);                                              \
    static void MulticueFuzz_##name(const std::uint8_t* data, std::size_t size)
