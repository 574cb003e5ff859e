#include "multicue/io/json_text.hpp"

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"

namespace multicue::io {

nlohmann::json ParseJsonText(std::string_view text, const std::string& source,
                             const JsonTextOptions& options) {
    // The parser reports the depth of every value it starts; refusing there bounds the nesting
    // before anything recursive runs over the document.
    const auto limit_depth = [&](int depth, nlohmann::json::parse_event_t event, nlohmann::json&) {
        if ((event == nlohmann::json::parse_event_t::object_start ||
             event == nlohmann::json::parse_event_t::array_start) &&
            depth >= options.max_depth) {
            throw FormatError(
                fmt::format("{}: JSON nested deeper than {} levels", source, options.max_depth));
        }
        return true;
    };
    try {
        return nlohmann::json::parse(text.begin(), text.end(), limit_depth,
                                     /*allow_exceptions=*/true, options.allow_comments);
    } catch (const nlohmann::json::exception& e) {
        std::string what = e.what();
        const auto pos = what.find("parse error");
        throw FormatError(fmt::format("{}: malformed JSON: {}", source,
                                      pos == std::string::npos ? what : what.substr(pos)));
    }
}

nlohmann::json ReadJsonFile(const std::filesystem::path& path, const JsonTextOptions& options) {
    return ParseJsonText(ReadFileBytes(path), path.string(), options);
}

}  // namespace multicue::io
