#include "multicue/ml/serialization.hpp"

#include <array>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include <signal.h>
#include <unistd.h>

namespace multicue::ml {

static_assert(std::endian::native == std::endian::little,
              "the ml binary formats are little-endian; add byte swapping for this platform");

namespace {

constexpr std::size_t kHeaderSize = 8 + 4 + 4 + 8 + 4;

std::array<std::uint32_t, 256> MakeCrcTable() {
    std::array<std::uint32_t, 256> table{};
    for (std::uint32_t i = 0; i < 256; ++i) {
        std::uint32_t c = i;
        for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        table[i] = c;
    }
    return table;
}

}  // namespace

std::uint32_t Crc32(std::string_view bytes) {
    static const auto table = MakeCrcTable();
    std::uint32_t c = 0xFFFFFFFFu;
    for (unsigned char b : bytes) c = table[(c ^ b) & 0xFFu] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}

void ByteWriter::PutString(std::string_view s) {
    Put<std::uint64_t>(s.size());
    buffer_.append(s.data(), s.size());
}

void ByteWriter::PutStrings(const std::vector<std::string>& v) {
    Put<std::uint64_t>(v.size());
    for (const auto& s : v) PutString(s);
}

std::string ByteReader::GetString() {
    const auto n = Get<std::uint64_t>();
    if (n > bytes_.size() - pos_) Fail("bad string length");
    std::string s(bytes_.substr(pos_, n));
    pos_ += n;
    return s;
}

std::vector<std::string> ByteReader::GetStrings() {
    const auto n = Get<std::uint64_t>();
    // Each string needs at least its 8-byte length.
    if (n > (bytes_.size() - pos_) / 8) Fail("bad string count");
    std::vector<std::string> v;
    v.reserve(n);
    for (std::uint64_t i = 0; i < n; ++i) v.push_back(GetString());
    return v;
}

void ByteReader::Fail(const std::string& problem) const {
    throw FormatError(what_ + ": " + problem + " (file corrupt or written by another program)");
}

std::string WrapContainer(std::string_view magic, std::uint32_t version, std::string_view payload) {
    if (magic.size() != 8) throw InvalidArgument("container magic must have 8 bytes");
    ByteWriter w;
    w.bytes().append(magic);
    w.Put<std::uint32_t>(version);
    w.Put<std::uint32_t>(0);
    w.Put<std::uint64_t>(payload.size());
    w.Put<std::uint32_t>(Crc32(payload));
    w.bytes().append(payload);
    return std::move(w.bytes());
}

void WriteContainer(const std::filesystem::path& path, std::string_view magic,
                    std::uint32_t version, std::string_view payload) {
    WriteBytesAtomically(path, WrapContainer(magic, version, payload));
}

std::uint32_t ContainerVersion(std::string_view bytes) {
    if (bytes.size() < 12) return 0;
    ByteReader r(bytes.substr(8, 4), "container header");
    return r.Get<std::uint32_t>();
}

std::string UnwrapContainer(std::string_view bytes, std::string_view magic, std::uint32_t version,
                            std::string_view kind, const std::string& what) {
    const std::string k(kind);
    if (bytes.size() < 8 || bytes.substr(0, 8) != magic) {
        throw FormatError(what + ": not a multicue " + k + " file (bad magic)");
    }
    if (bytes.size() < kHeaderSize) throw FormatError(what + ": truncated " + k + " header");
    ByteReader r(bytes.substr(8, kHeaderSize - 8), what);
    const auto file_version = r.Get<std::uint32_t>();
    r.Get<std::uint32_t>();
    const auto size = r.Get<std::uint64_t>();
    const auto crc = r.Get<std::uint32_t>();
    if (file_version != version) {
        throw FormatError(what + ": " + k + " format version " + std::to_string(file_version) +
                          " is not supported (this build reads version " + std::to_string(version) +
                          ")");
    }
    if (size != bytes.size() - kHeaderSize) {
        throw FormatError(what + ": " + k + " file is truncated or has trailing bytes (payload " +
                          std::to_string(bytes.size() - kHeaderSize) + " bytes, header says " +
                          std::to_string(size) + ")");
    }
    const auto payload = bytes.substr(kHeaderSize);
    if (Crc32(payload) != crc) throw FormatError(what + ": " + k + " file is corrupt (checksum)");
    return std::string(payload);
}

std::string ReadContainer(const std::filesystem::path& path, std::string_view magic,
                          std::uint32_t version, std::string_view kind) {
    return UnwrapContainer(ReadBytes(path), magic, version, kind, path.string());
}

std::string ReadBytes(const std::filesystem::path& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        throw IoError(path.string() + ": is a directory");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path.string() + ": cannot open for reading");
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw IoError(path.string() + ": read failed");
    return std::move(ss).str();
}

namespace {

// Removes the temporary files of `name` in `dir` left by killed writers (their process is gone);
// as io::WriteFileAtomically does for its own.
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

void WriteBytesAtomically(const std::filesystem::path& path, std::string_view bytes) {
    static std::atomic<unsigned> counter{0};
    auto dir = path.parent_path();
    if (dir.empty()) dir = ".";
    // Hidden and named like io::WriteFileAtomically's, so a file left by a killed process is
    // recognisable as one.
    RemoveStaleTemporaries(dir, path.filename().string());
    std::string name = ".";
    name.append(path.filename().string());
    name.append(".tmp-").append(std::to_string(::getpid()));
    name.append("-").append(std::to_string(counter++));
    const auto tmp = dir / name;
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) {
            throw IoError(path.string() + ": cannot open for writing: " + std::strerror(errno));
        }
        errno = 0;
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        out.close();
        if (!out) {
            // errno of the failed write: ENOSPC (disk full), EFBIG (ulimit -f), EIO, ...
            const std::string why = errno != 0 ? std::strerror(errno) : "stream error";
            std::error_code ec;
            std::filesystem::remove(tmp, ec);
            throw IoError(path.string() + ": write failed: " + why);
        }
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        std::filesystem::remove(tmp, ec);
        throw IoError(path.string() + ": cannot replace file: " + ec.message());
    }
}

}  // namespace multicue::ml
