#pragma once
// Command lines of the accuracy drivers (CLI11): --help prints the usage, a bad option or value
// is one line on stderr and exit code 2, as for the multicue CLI.

#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace multicue::eval {

/// Runs `parse` (app.parse and any checks that throw CLI::ParseError). Returns the exit code when
/// the program should stop (0 after --help), nothing when it should go on.
template <typename Parse>
std::optional<int> ParseDriverOptions(CLI::App& app, const char* name, Parse&& parse) {
    try {
        parse();
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
        std::fprintf(stderr, "%s: %s (run with --help for usage)\n", name, e.what());
        return 2;
    }
    return std::nullopt;
}

/// The non-empty items of a comma-separated list ("a,,b" gives a and b).
inline std::vector<std::string> SplitComma(const std::string& s) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    while (start <= s.size()) {
        const std::size_t end = std::min(s.find(',', start), s.size());
        if (end > start) parts.push_back(s.substr(start, end - start));
        start = end + 1;
    }
    return parts;
}

}  // namespace multicue::eval
