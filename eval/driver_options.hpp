#pragma once
// Command lines of the accuracy drivers (CLI11): --help prints the usage, a bad option or value
// is one line on stderr and exit code 2, as for the multicue CLI.

#include <cstdio>
#include <optional>

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

}  // namespace multicue::eval
