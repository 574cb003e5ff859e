// Replays the regression inputs of every fuzz target (fuzz/regression/<target>/): each input once
// crashed, hung or leaked in a reader. Built with any compiler, as part of the normal tests.

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "fuzz_target.hpp"
#include "multicue/core/logging.hpp"

namespace multicue::fuzz {
namespace {

namespace fs = std::filesystem;

const fs::path kRegressionDir = MULTICUE_FUZZ_REGRESSION_DIR;

std::vector<std::string> ListedTargets() {
    std::vector<std::string> names;
    std::stringstream ss(MULTICUE_FUZZ_TARGET_NAMES);
    std::string name;
    while (std::getline(ss, name, ',')) names.push_back(name);
    return names;
}

std::string ReadAll(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class SilentLog : public testing::Environment {
  public:
    void SetUp() override {
        SetLogSink([](LogLevel, std::string_view) {});
    }
};
const auto* const kSilentLog = testing::AddGlobalTestEnvironment(new SilentLog);

TEST(FuzzTargets, EveryListedTargetIsRegisteredUnderItsName) {
    for (const auto& name : ListedTargets()) {
        EXPECT_EQ(Targets().count(name), 1u)
            << "fuzz/targets/" << name << ".cpp must define MULTICUE_FUZZ_TARGET(" << name << ")";
    }
    EXPECT_EQ(Targets().size(), ListedTargets().size());
}

TEST(FuzzTargets, EveryRegressionFolderBelongsToATarget) {
    if (!fs::is_directory(kRegressionDir)) GTEST_SKIP() << "no regression inputs";
    for (const auto& entry : fs::directory_iterator(kRegressionDir)) {
        if (entry.is_directory()) {
            EXPECT_EQ(Targets().count(entry.path().filename().string()), 1u)
                << entry.path() << " has no fuzz target of that name";
        }
    }
}

TEST(FuzzTargets, EmptyAndTinyInputsAreRefusedCleanly) {
    for (const auto& [name, entry] : Targets()) {
        for (const std::string& input : {std::string(), std::string(1, '\0'), std::string("\n"),
                                         std::string("{}"), std::string("[]")}) {
            EXPECT_NO_THROW(
                entry(reinterpret_cast<const std::uint8_t*>(input.data()), input.size()))
                << name << " on '" << input << "'";
        }
    }
}

class Replay : public testing::TestWithParam<std::string> {};

TEST_P(Replay, RegressionInputsAreHandled) {
    const std::string& name = GetParam();
    const Entry entry = Targets().at(name);
    const fs::path dir = kRegressionDir / name;
    if (!fs::is_directory(dir)) GTEST_SKIP() << "no regression inputs for " << name;
    std::vector<fs::path> files;
    for (const auto& f : fs::directory_iterator(dir)) {
        if (f.is_regular_file()) files.push_back(f.path());
    }
    std::sort(files.begin(), files.end());
    for (const auto& file : files) {
        const std::string bytes = ReadAll(file);
        const auto start = std::chrono::steady_clock::now();
        EXPECT_NO_THROW(entry(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()))
            << file;
        const double s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        RecordProperty(file.filename().string(), std::to_string(s));
    }
}

INSTANTIATE_TEST_SUITE_P(Fuzz, Replay, testing::ValuesIn(ListedTargets()),
                         [](const testing::TestParamInfo<std::string>& param) {
                             return param.param;
                         });

}  // namespace
}  // namespace multicue::fuzz
