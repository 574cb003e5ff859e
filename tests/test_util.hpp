#pragma once
// Helpers shared by the tests: deterministic synthetic clouds, temporary folders, shared data.

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <random>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include "multicue/core/point_cloud.hpp"
#include "test_paths.hpp"

namespace multicue::test {

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// Path of a file under the shared data folder; skips the test if the folder is absent.
inline std::filesystem::path SharedData(const std::string& relative) {
    return std::filesystem::path(SharedDataDir()) / relative;
}
inline bool HasSharedData() { return std::filesystem::is_directory(SharedDataDir()); }

/// A fresh, empty temporary folder, removed when the object goes out of scope.
class TempDir {
  public:
    TempDir() {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        std::string name = "multicue-test";
        if (info != nullptr)
            name += std::string("-") + info->test_suite_name() + "-" + info->name();
        for (auto& c : name) {
            if (c == '/') c = '_';
        }
        // The process id keeps test runs of several checkouts (or builds) on one machine apart.
        name += '-';
        name += std::to_string(::getpid());
        path_ = std::filesystem::temp_directory_path() / name;
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }
    std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

  private:
    std::filesystem::path path_;
};

/// Uniform random points in a box, fixed seed.
inline PointCloud RandomCloud(std::size_t n, std::uint32_t seed = 1, float extent = 1.0f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-extent, extent);
    PointCloud c;
    c.points.resize(n);
    for (auto& p : c.points) p = {u(rng), u(rng), u(rng)};
    c.SetUnorganized();
    return c;
}

}  // namespace multicue::test
