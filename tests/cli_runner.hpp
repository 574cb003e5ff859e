#pragma once
// Runs the multicue command-line tool from tests and captures its output and exit code.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "test_paths.hpp"

namespace multicue::test {

struct CliResult {
    int code = -1;
    std::string output;  // stdout and stderr together
};

/// `args` are appended to the tool's path as given (quote paths with spaces yourself).
inline CliResult RunCli(const std::string& args) {
    const std::string command = std::string(CliPath()) + " " + args + " 2>&1";
    CliResult r;
    FILE* pipe = ::popen(command.c_str(), "r");
    if (pipe == nullptr) return r;
    std::array<char, 4096> buf{};
    while (std::fgets(buf.data(), buf.size(), pipe) != nullptr) r.output += buf.data();
    const int status = ::pclose(pipe);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

inline std::string ReadTextFile(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace multicue::test
