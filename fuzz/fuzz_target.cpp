#include "fuzz_target.hpp"

#include <fstream>
#include <system_error>

#include <unistd.h>

#include "multicue/ml/serialization.hpp"

namespace multicue::fuzz {

std::map<std::string, Entry>& Targets() {
    static std::map<std::string, Entry> targets;
    return targets;
}

std::filesystem::path WriteInput(std::string_view bytes, const std::string& name) {
    // One folder per process (libFuzzer's -fork and -jobs run several), in memory when /dev/shm
    // is there.
    struct Folder {
        std::filesystem::path path;
        Folder() {
            std::error_code ec;
            const std::filesystem::path shm = "/dev/shm";
            const auto base = std::filesystem::is_directory(shm, ec)
                                  ? shm
                                  : std::filesystem::temp_directory_path();
            path = base / ("multicue-fuzz-" + std::to_string(::getpid()));
            std::filesystem::create_directories(path);
        }
        ~Folder() {
            std::error_code ec;
            std::filesystem::remove_all(path, ec);
        }
    };
    static const Folder dir;
    const auto path = dir.path / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) throw std::runtime_error("cannot write the fuzz input to " + path.string());
    return path;
}

std::filesystem::path WriteContainerInput(std::string_view bytes, std::string_view magic,
                                          std::uint32_t version, const std::string& name) {
    if (bytes.substr(0, magic.size()) == magic) return WriteInput(bytes, name);
    return WriteInput(ml::WrapContainer(magic, version, bytes), name);
}

}  // namespace multicue::fuzz
