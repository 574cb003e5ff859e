#include "multicue/core/atomic_file.hpp"

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <system_error>

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include "multicue/core/exceptions.hpp"

namespace multicue {

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

}  // namespace multicue
