#include "multicue/io/file_utils.hpp"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <system_error>

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

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

namespace {

// Removes the temporary files of `path` (".NAME.tmp-PID-N") left by writers that were killed: their
// process is gone. Files of a live process with that id (a writer now, or an unrelated process
// that got the id) are left alone.
void RemoveStaleTemporaries(const std::filesystem::path& dir, const std::string& name) {
    const std::string prefix = "." + name + ".tmp-";
    std::error_code ec;
    for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string file = it->path().filename().string();
        if (file.rfind(prefix, 0) != 0) continue;
        const long pid = std::strtol(file.c_str() + prefix.size(), nullptr, 10);
        if (pid > 0 && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
            std::error_code remove_ec;
            std::filesystem::remove(it->path(), remove_ec);
        }
    }
}

}  // namespace

void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write) {
    static std::atomic<unsigned> counter{0};
    const auto dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec)) {
        throw IoError(fmt::format("{}: folder '{}' does not exist", path.string(), dir.string()));
    }
    RemoveStaleTemporaries(dir, path.filename().string());
    const auto tmp = dir / fmt::format(".{}.tmp-{}-{}", path.filename().string(),
                                       static_cast<long>(::getpid()), counter.fetch_add(1));
    try {
        {
            std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
            if (!out) {
                throw IoError(fmt::format("{}: cannot open for writing: {}", path.string(),
                                          std::strerror(errno)));
            }
            errno = 0;
            write(out);
            out.close();
            if (!out) {
                // errno of the failed write: ENOSPC (disk full), EFBIG (ulimit -f), EIO, ...
                throw IoError(fmt::format("{}: write failed: {}", path.string(),
                                          errno != 0 ? std::strerror(errno) : "stream error"));
            }
        }
        std::filesystem::rename(tmp, path, ec);
        if (ec) {
            throw IoError(fmt::format("{}: cannot replace file: {}", path.string(), ec.message()));
        }
    } catch (...) {
        std::filesystem::remove(tmp, ec);
        throw;
    }
}

std::string LowerExtension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    if (!ext.empty() && ext.front() == '.') ext.erase(0, 1);
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

}  // namespace multicue::io
