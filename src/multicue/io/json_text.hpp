#pragma once
/// \file JSON documents from files people and other programs write (parameter files, manifests,
/// database exports): parse errors and absurd nesting become one-line errors naming the source.

#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>

#include <nlohmann/json.hpp>

namespace multicue::io {

/// Deepest nesting of arrays and objects a document may have. Every walk over a document
/// (dumping it, comparing it, checking its keys) recurses once per level, so a file of a few
/// hundred kilobytes of '[' could otherwise exhaust the stack.
inline constexpr int kMaxJsonDepth = 64;

struct JsonTextOptions {
    bool allow_comments = false;    ///< accept `//` and `/* */` comments
    int max_depth = kMaxJsonDepth;  ///< deepest nesting of arrays and objects [levels]
};

/// Parses `text` as one JSON document. Throws FormatError naming `source` when it is malformed or
/// nested deeper than options.max_depth.
nlohmann::json ParseJsonText(std::string_view text, const std::string& source,
                             const JsonTextOptions& options = {});

/// Reads and parses a JSON file (ReadFileBytes, then ParseJsonText). Throws IoError or
/// FormatError naming the file.
/// Whether a JSON integer lies within the range of the integer type T (a cast would otherwise
/// silently make another value of it).
template <typename T>
bool JsonIntegerFits(const nlohmann::json& j) {
    if (!j.is_number_integer()) return false;
    if (j.is_number_unsigned()) {
        return j.get<std::uint64_t>() <= static_cast<std::uint64_t>(std::numeric_limits<T>::max());
    }
    const auto v = j.get<std::int64_t>();
    if constexpr (std::is_unsigned_v<T>) {
        return v >= 0 && static_cast<std::uint64_t>(v) <=
                             static_cast<std::uint64_t>(std::numeric_limits<T>::max());
    } else {
        return v >= static_cast<std::int64_t>(std::numeric_limits<T>::lowest()) &&
               v <= static_cast<std::int64_t>(std::numeric_limits<T>::max());
    }
}

nlohmann::json ReadJsonFile(const std::filesystem::path& path, const JsonTextOptions& options = {});

}  // namespace multicue::io
