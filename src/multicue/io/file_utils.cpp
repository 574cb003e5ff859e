#include "multicue/io/file_utils.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <system_error>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue::io {

std::string ReadFileBytes(const std::filesystem::path& path) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status)) {
        throw IoError(fmt::format("{}: no such file", path.string()));
    }
    if (std::filesystem::is_directory(status)) {
        throw IoError(fmt::format("{}: is a directory, not a file", path.string()));
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(fmt::format("{}: cannot open for reading", path.string()));
    std::string bytes;
    const auto size = std::filesystem::file_size(path, ec);
    if (!ec) {
        // One block read: reading through istreambuf_iterator goes byte by byte.
        bytes.resize(static_cast<std::size_t>(size));
        in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        bytes.resize(static_cast<std::size_t>(in.gcount()));
    }
    // Whatever is left: the whole file if its size is unknown, or what it grew by meanwhile.
    if (!in.eof())
        bytes.append(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (in.bad()) throw IoError(fmt::format("{}: read error", path.string()));
    return bytes;
}

std::string LowerExtension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    if (!ext.empty() && ext.front() == '.') ext.erase(0, 1);
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

}  // namespace multicue::io
