#pragma once
// Where the tests find the command-line tool and the shared data. The values are written by CMake
// into one generated source file (test_paths.cpp in the build folder), so that no test's compile
// command carries an absolute path and a compiler cache serves checkouts in any folder.

namespace multicue::test {

/// The shared data folder (scans, meshes); it may be absent.
const char* SharedDataDir();
/// The `multicue` executable of this build.
const char* CliPath();

}  // namespace multicue::test
