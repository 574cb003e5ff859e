// Readers refuse what a file cannot hold or what would exhaust memory or stack, at once and with
// a message naming the file: headers claiming 10^12 points, absurd nesting, YAML alias bombs,
// numbers beyond the range of the value they set. Each case once reached a reader's limits (most
// were found by the fuzz targets in fuzz/).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <fmt/format.h>
#include <unistd.h>

#include "ml_test_data.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/config.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/json_text.hpp"
#include "multicue/io/pcd.hpp"
#include "multicue/io/ply.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/ml/dataset.hpp"
#include "multicue/ml/svm_model_text.hpp"
#include "multicue/system/perceive.hpp"
#include "sim_manifest.hpp"
#include "task_file.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

std::filesystem::path Write(const test::TempDir& dir, const std::string& name,
                            const std::string& bytes) {
    const auto path = dir / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

template <typename Exception, typename Body>
void ExpectMessage(Body&& body, const std::string& part) {
    try {
        body();
        ADD_FAILURE() << "no exception, expected one containing '" << part << "'";
    } catch (const Exception& e) {
        EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
}

constexpr const char* kTrillion = "WIDTH 1000000\nHEIGHT 1000000\nPOINTS 1000000000000\n";

TEST(InputLimits, PcdHeaderClaimingATrillionPointsIsRefused) {
    const test::TempDir dir;
    const std::string fields = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
    for (const std::string encoding : {"ascii", "binary", "binary_compressed"}) {
        const auto path = Write(dir, encoding + ".pcd",
                                fields + kTrillion + "DATA " + encoding + "\n1 2 3\n4 5 6\n");
        EXPECT_THROW(io::ReadPcd(path), FormatError) << encoding;
    }
    ExpectMessage<FormatError>(
        [&] {
            io::ReadPcd(Write(dir, "a.pcd", fields + kTrillion + "DATA ascii\n1 2 3\n4 5 6\n"));
        },
        "1000000000000 points claimed, 12 bytes of data hold at most 6");
    // POINTS alone stands for WIDTH in very old files; beyond 32 bits it is refused.
    ExpectMessage<FormatError>(
        [&] {
            io::ReadPcd(Write(dir, "p.pcd",
                              fields + "POINTS 1000000000000\nDATA binary\n" + std::string(12, 0)));
        },
        "too large");
}

TEST(InputLimits, PlyElementCountBeyondTheFileIsRefused) {
    const test::TempDir dir;
    const std::string header =
        "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n";
    const auto path = Write(dir, "v.ply", header + std::string(24, '\0'));
    EXPECT_THROW(io::ReadPly(path), FormatError);
    EXPECT_THROW(io::ReadPlyMesh(path), FormatError);
}

TEST(InputLimits, JsonNestingIsBounded) {
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    ExpectMessage<FormatError>([&] { io::ParseJsonText(deep, "deep.json"); },
                               "deep.json: JSON nested deeper than 64 levels");
    const std::string ok =
        std::string(io::kMaxJsonDepth, '[') + std::string(io::kMaxJsonDepth, ']');
    EXPECT_NO_THROW(io::ParseJsonText(ok, "ok.json"));
    EXPECT_THROW(io::ParseJsonText("{\"a\":" + deep + "}", "a.json"), FormatError);
    ExpectMessage<FormatError>([] { io::ParseJsonText("{\"a\": tru}", "t.json"); },
                               "t.json: malformed JSON");
}

TEST(InputLimits, ParameterFileNumbersMustFitTheirParameter) {
    const auto read = [](const std::string& text) {
        auto config = io::ConfigSection::Parse(text, "p.json");
        PerceiveParams params;
        ReadPerceiveParams(config, params);
        config.CheckAllUsed();
    };
    EXPECT_NO_THROW(read(R"({"threads": 2, "prism": {"min_height": 0.01}})"));
    // int: 2^40 would wrap; float: 1e300 would be infinite (undefined as a conversion).
    ExpectMessage<InvalidArgument>([&] { read(R"({"threads": 1099511627776})"); }, "'threads'");
    ExpectMessage<InvalidArgument>([&] { read(R"({"prism": {"min_height": 1e300}})"); },
                                   "'prism.min_height' must be a finite number");
    ExpectMessage<InvalidArgument>([&] { read(R"({"support": {"up": [0, 1e39, 0]}})"); },
                                   "'support.up'");
    // Deep nesting in a parameter file is a usage error naming the file.
    ExpectMessage<InvalidArgument>([&] { read("{\"a\":" + std::string(200, '[') + "}"); },
                                   "p.json: JSON nested deeper");
}

TEST(InputLimits, YamlAliasesCannotExpandWithoutBound) {
    const test::TempDir dir;
    // Each level doubles the values the aliases stand for: 2^40 at the end.
    std::string bomb = "a0: &a0 [x, x]\n";
    for (int i = 1; i <= 40; ++i) {
        bomb += fmt::format("a{0}: &a{0} [*a{1}, *a{1}]\n", i, i - 1);
    }
    bomb += "frames: [f.pcd]\n";
    ExpectMessage<FormatError>([&] { cli::ReadTaskFile(Write(dir, "bomb.yaml", bomb)); },
                               "aliases expand to too many values");
    const std::string deep = "frames: " + std::string(200, '[') + std::string(200, ']') + "\n";
    ExpectMessage<FormatError>([&] { cli::ReadTaskFile(Write(dir, "deep.yaml", deep)); },
                               "nested deeper");
}

TEST(InputLimits, TaskPosesAndTimesMustBeFinite) {
    const test::TempDir dir;
    const auto task = [&](const std::string& frame) {
        return cli::ReadTaskFile(Write(dir, "t.yaml", "frames:\n  - " + frame + "\n"));
    };
    EXPECT_NO_THROW(task("{file: a.pcd, pose: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}"));
    EXPECT_THROW(task("{file: a.pcd, pose: [nan,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}"),
                 InvalidArgument);
    EXPECT_THROW(task("{file: a.pcd, pose: [1e999,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}"),
                 InvalidArgument);
    EXPECT_THROW(task("{file: a.pcd, time: .inf}"), InvalidArgument);
}

TEST(InputLimits, ManifestPosesMustBeFiniteSinglePrecisionValues) {
    const std::string frame =
        R"({"file": "f.pcd", "T_world_sensor": [[1,0,0,X],[0,1,0,0],[0,0,1,0],[0,0,0,1]]})";
    const auto manifest = [&](const std::string& x) {
        std::string f = frame;
        f.replace(f.find('X'), 1, x);
        return cli::ParseSimManifest(R"({"scenes": [{"id": 3, "frames": [)" + f + "]}]}", "m.json");
    };
    const auto scenes = manifest("0.5");
    ASSERT_EQ(scenes.size(), 1u);
    EXPECT_EQ(scenes[0].id, 3);
    EXPECT_EQ(scenes[0].frames.at(0).T_world_sensor(0, 3), 0.5);
    ExpectMessage<FormatError>([&] { manifest("1e300"); }, "not a finite number");
    ExpectMessage<FormatError>([&] { manifest("\"x\""); }, "not a finite number");
    EXPECT_THROW(cli::ParseSimManifest(R"({"scenes": [{"frames": {"a": 1}}]})", "m.json"),
                 FormatError);
    EXPECT_THROW(cli::ParseSimManifest(R"({"scenes": [7]})", "m.json"), FormatError);
}

TEST(InputLimits, LibsvmModelTextIsCheckedBeforeLibsvmReadsIt) {
    const ml::Dataset data = test::Blobs(3, 4, 2, 5, 0.3f);
    const auto svm = ml::CreateClassifier("svm:kernel=rbf");
    svm->Fit(data);
    const std::string bytes = svm->Serialize();
    const std::string text = bytes.substr(bytes.find("svm_type"));
    EXPECT_EQ(ml::SvmModelTextProblem(text, 5, 3), "");
    const auto broken = [&](const std::string& from, const std::string& to) {
        std::string t = text;
        const auto at = t.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        return ml::SvmModelTextProblem(t.replace(at, from.size(), to), 5, 3);
    };
    EXPECT_NE(broken("nr_sv ", "nr_sv 1000 "), "");
    EXPECT_NE(broken("kernel_type rbf", "kernel_type poly"), "");
    EXPECT_NE(broken("nr_class 3", "nr_class 4"), "");
    EXPECT_NE(broken("label 0", "label 9"), "");
    EXPECT_NE(broken("SV\n", "SV\n1\n"), "");  // a line without coefficients
    EXPECT_NE(broken("1:", "6:"), "");         // beyond the 5 features
    EXPECT_NE(broken("rho ", "rho nan "), "");
    EXPECT_NE(ml::SvmModelTextProblem(text.substr(0, text.size() - 40), 5, 3), "");  // cut
    EXPECT_NE(ml::SvmModelTextProblem("", 5, 3), "");
    EXPECT_NE(ml::SvmModelTextProblem(text, 5, 2), "");  // more classes than the model has
}

TEST(AtomicWrites, TemporariesOfKilledWritersAreRemovedByTheNextWrite) {
    const test::TempDir dir;
    // No process has the id 999999999 (beyond any pid_max); the current process is alive.
    const auto dead = dir / ".out.pcd.tmp-999999999-0";
    const auto dead_model = dir / ".m.mcd.tmp-999999999-3";
    const auto alive = dir / (".out.pcd.tmp-" + std::to_string(::getpid()) + "-7");
    const auto other = dir / ".other.pcd.tmp-999999999-0";
    for (const auto& p : {dead, dead_model, alive, other}) std::ofstream(p) << "half";
    PointCloud c;
    c.points = {Eigen::Vector3f(1, 2, 3)};
    c.SetUnorganized();
    io::WritePcd(dir / "out.pcd", c);
    EXPECT_FALSE(std::filesystem::exists(dead));
    EXPECT_TRUE(std::filesystem::exists(alive));
    EXPECT_TRUE(std::filesystem::exists(other));  // another file's: left to its own next write
    ml::Dataset d = test::Blobs(2, 2, 1, 3, 0.1f);
    ml::SaveDataset(d, dir / "m.mcd");
    EXPECT_FALSE(std::filesystem::exists(dead_model));
    EXPECT_EQ(io::ReadPcd(dir / "out.pcd").size(), 1u);
}

TEST(AtomicWrites, AFailedWriteNamesTheFileAndTheReasonAndKeepsTheOldFile) {
    const test::TempDir dir;
    const auto path = dir / "keep.txt";
    std::ofstream(path) << "old";
    try {
        io::WriteFileAtomically(path, [](std::ostream& out) {
            out << "new";
            out.setstate(std::ios::badbit);  // as a full disk leaves the stream
        });
        ADD_FAILURE() << "no error";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("keep.txt: write failed"), std::string::npos)
            << e.what();
    }
    std::ifstream in(path);
    std::string text;
    in >> text;
    EXPECT_EQ(text, "old");
    for (const auto& f : std::filesystem::directory_iterator(dir.path())) {
        EXPECT_EQ(f.path().filename(), "keep.txt");  // no temporary file left
    }
}

}  // namespace
}  // namespace multicue
