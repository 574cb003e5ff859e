#pragma once
/// \file Versioned binary containers shared by every ml artefact (datasets, models, transforms).
///
/// Layout (little-endian): 8-byte magic naming the artefact, u32 format version, u32 reserved (0),
/// u64 payload size, u32 CRC-32 of the payload, then the payload. Readers refuse another magic,
/// another version, a size that does not match the file and a checksum mismatch, each with a
/// one-line FormatError naming the file. Files are written atomically (temporary file + rename).

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "multicue/core/exceptions.hpp"

namespace multicue::ml {

/// CRC-32 (IEEE 802.3 polynomial, as zlib and PNG use).
std::uint32_t Crc32(std::string_view bytes);

/// Appends plain values to a byte buffer.
class ByteWriter {
  public:
    template <typename T>
    void Put(T value) {
        static_assert(std::is_trivially_copyable_v<T>);
        const auto* p = reinterpret_cast<const char*>(&value);
        buffer_.append(p, sizeof(T));
    }
    template <typename T>
    void PutArray(const T* data, std::size_t count) {
        static_assert(std::is_trivially_copyable_v<T>);
        Put<std::uint64_t>(count);
        buffer_.append(reinterpret_cast<const char*>(data), count * sizeof(T));
    }
    template <typename T>
    void PutVector(const std::vector<T>& v) {
        PutArray(v.data(), v.size());
    }
    void PutString(std::string_view s);
    void PutStrings(const std::vector<std::string>& v);
    const std::string& bytes() const { return buffer_; }
    std::string& bytes() { return buffer_; }

  private:
    std::string buffer_;
};

/// Reads values written by ByteWriter; every read is bounds-checked and throws FormatError
/// naming `what` (usually the file) when the payload is truncated or inconsistent.
class ByteReader {
  public:
    ByteReader(std::string_view bytes, std::string what) : bytes_(bytes), what_(std::move(what)) {}

    template <typename T>
    T Get() {
        static_assert(std::is_trivially_copyable_v<T>);
        Need(sizeof(T));
        T value;
        std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
        pos_ += sizeof(T);
        return value;
    }
    template <typename T>
    std::vector<T> GetVector(std::uint64_t max_count = UINT64_MAX) {
        const auto count = Get<std::uint64_t>();
        if (count > max_count || count > (bytes_.size() - pos_) / sizeof(T)) Fail("bad array size");
        std::vector<T> v(count);
        if (count > 0) std::memcpy(v.data(), bytes_.data() + pos_, count * sizeof(T));
        pos_ += count * sizeof(T);
        return v;
    }
    std::string GetString();
    std::vector<std::string> GetStrings();
    bool AtEnd() const { return pos_ == bytes_.size(); }
    [[noreturn]] void Fail(const std::string& problem) const;
    const std::string& what() const { return what_; }

  private:
    void Need(std::size_t n) const {
        if (bytes_.size() - pos_ < n) Fail("truncated payload");
    }
    std::string_view bytes_;
    std::size_t pos_ = 0;
    std::string what_;
};

/// Wraps `payload` into a container and writes it atomically to `path`.
void WriteContainer(const std::filesystem::path& path, std::string_view magic,
                    std::uint32_t version, std::string_view payload);

/// Reads a container, checks magic, version, size and checksum, returns the payload.
/// `kind` names the artefact in messages ("dataset", "classifier model").
std::string ReadContainer(const std::filesystem::path& path, std::string_view magic,
                          std::uint32_t version, std::string_view kind);

/// Same checks on bytes already in memory (`what` names them in messages).
/// The format version in a container's header; 0 when `bytes` are too short to hold one.
std::uint32_t ContainerVersion(std::string_view bytes);
std::string UnwrapContainer(std::string_view bytes, std::string_view magic, std::uint32_t version,
                            std::string_view kind, const std::string& what);
/// Container bytes for `payload` (what WriteContainer writes).
std::string WrapContainer(std::string_view magic, std::uint32_t version, std::string_view payload);

/// Writes `bytes` to `path` through a temporary file in the same folder, renamed on success.
void WriteBytesAtomically(const std::filesystem::path& path, std::string_view bytes);
/// Reads a whole file; IoError naming it when missing or unreadable.
std::string ReadBytes(const std::filesystem::path& path);

}  // namespace multicue::ml
