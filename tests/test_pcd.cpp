#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/pcd.hpp"
#include "test_util.hpp"

namespace multicue::io {
void PrintTo(PcdEncoding e, std::ostream* os) { *os << static_cast<int>(e); }
}  // namespace multicue::io

namespace multicue {
namespace {

namespace fs = std::filesystem;
using io::PcdEncoding;
using io::ReadPcd;
using io::WritePcd;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// ------------------------------------------------------------------------------------ helpers

std::string ReadBytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void WriteBytes(const fs::path& p, const std::string& bytes) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// Same bits, or both NaN.
bool SameFloat(float a, float b) {
    return (std::isnan(a) && std::isnan(b)) ||
           std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

::testing::AssertionResult SameVectors(const std::vector<Eigen::Vector3f>& a,
                                       const std::vector<Eigen::Vector3f>& b) {
    if (a.size() != b.size()) {
        return ::testing::AssertionFailure() << "sizes " << a.size() << " vs " << b.size();
    }
    for (std::size_t i = 0; i < a.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            if (!SameFloat(a[i][k], b[i][k])) {
                return ::testing::AssertionFailure()
                       << "entry " << i << "[" << k << "]: " << a[i][k] << " vs " << b[i][k];
            }
        }
    }
    return ::testing::AssertionSuccess();
}

::testing::AssertionResult SameFloats(const std::vector<float>& a, const std::vector<float>& b) {
    if (a.size() != b.size()) {
        return ::testing::AssertionFailure() << "sizes " << a.size() << " vs " << b.size();
    }
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (!SameFloat(a[i], b[i])) {
            return ::testing::AssertionFailure() << "entry " << i << ": " << a[i] << " vs " << b[i];
        }
    }
    return ::testing::AssertionSuccess();
}

void ExpectSameCloud(const PointCloud& a, const PointCloud& b) {
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_TRUE(SameVectors(a.points, b.points)) << "points";
    EXPECT_TRUE(SameVectors(a.normals, b.normals)) << "normals";
    EXPECT_TRUE(SameFloats(a.curvature, b.curvature)) << "curvature";
    EXPECT_TRUE(SameFloats(a.intensity, b.intensity)) << "intensity";
    EXPECT_TRUE(SameFloats(a.confidence, b.confidence)) << "confidence";
    EXPECT_TRUE(a.colors == b.colors) << "colors";
    EXPECT_EQ(a.labels, b.labels);
    ASSERT_EQ(a.extra_fields.size(), b.extra_fields.size());
    for (std::size_t i = 0; i < a.extra_fields.size(); ++i) {
        const auto& x = a.extra_fields[i];
        const auto& y = b.extra_fields[i];
        EXPECT_EQ(x.name, y.name);
        EXPECT_EQ(x.type, y.type) << x.name;
        EXPECT_EQ(x.size, y.size) << x.name;
        EXPECT_EQ(x.count, y.count) << x.name;
        EXPECT_TRUE(x.data == y.data) << x.name;
    }
    EXPECT_TRUE(SameVectors({a.sensor_origin}, {b.sensor_origin}));
    EXPECT_EQ(a.sensor_orientation.coeffs(), b.sensor_orientation.coeffs());
}

/// Floats that are hard to print and parse exactly.
float Tricky(std::size_t i, std::mt19937& rng) {
    static const float kSpecial[] = {0.0f,
                                     -0.0f,
                                     1.0f / 3.0f,
                                     std::numeric_limits<float>::max(),
                                     std::numeric_limits<float>::lowest(),
                                     std::numeric_limits<float>::min(),
                                     std::numeric_limits<float>::denorm_min(),
                                     1e-30f,
                                     123456.789f,
                                     -2.5e7f};
    if (i < std::size(kSpecial)) return kSpecial[i];
    return std::uniform_real_distribution<float>(-10.0f, 10.0f)(rng);
}

ExtraField MakeExtra(const std::string& name, char type, std::uint8_t size, std::uint32_t count,
                     std::size_t n, std::mt19937& rng) {
    ExtraField f{name, type, size, count, {}};
    f.data.resize(n * f.BytesPerPoint());
    for (std::size_t k = 0; k < n * count; ++k) {
        std::uint8_t* p = f.data.data() + k * size;
        if (type == 'F' && size == 8) {
            const double v = std::uniform_real_distribution<double>(-1e6, 1e6)(rng) / 3.0;
            std::memcpy(p, &v, 8);
        } else if (type == 'F') {
            const float v = std::uniform_real_distribution<float>(-1.0f, 1.0f)(rng);
            std::memcpy(p, &v, 4);
        } else {
            for (std::uint8_t b = 0; b < size; ++b) p[b] = static_cast<std::uint8_t>(rng());
        }
    }
    return f;
}

enum Fields : unsigned {
    kRgb = 1,
    kRgbaAlpha = 2,
    kNormals = 4,
    kLabels = 8,
    kIntensity = 16,
    kExtras = 32,
    kOrganized = 64,
};

/// A cloud with the requested fields; organized clouds are 4x3 with NaN points and a sensor pose.
PointCloud MakeCloud(unsigned fields, std::size_t n = 37, std::uint32_t seed = 3) {
    std::mt19937 rng(seed);
    PointCloud c;
    if (fields & kOrganized) n = 12;
    c.points.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        c.points[i] = {Tricky(i, rng), Tricky(i + 3, rng), Tricky(i + 5, rng)};
    }
    if (fields & kNormals) {
        c.normals.resize(n);
        std::normal_distribution<float> g;
        for (auto& v : c.normals) v = Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized();
        c.curvature.resize(n);
        for (std::size_t i = 0; i < n; ++i) c.curvature[i] = Tricky(i + 1, rng);
    }
    if (fields & (kRgb | kRgbaAlpha)) {
        c.colors.resize(n);
        for (auto& col : c.colors) {
            col = {static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()),
                   static_cast<std::uint8_t>(rng()),
                   static_cast<std::uint8_t>(fields & kRgbaAlpha ? rng() % 256 : 255)};
        }
        if (fields & kRgbaAlpha) c.colors[0].a = 0;
    }
    if (fields & kLabels) {
        c.labels.resize(n);
        for (std::size_t i = 0; i < n; ++i) c.labels[i] = i == 0 ? 0xffffffffu : rng() % 100;
    }
    if (fields & kIntensity) {
        c.intensity.resize(n);
        c.confidence.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            c.intensity[i] = Tricky(i + 2, rng);
            c.confidence[i] = std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
        }
    }
    if (fields & kExtras) {
        c.extra_fields.push_back(MakeExtra("ring", 'U', 1, 1, n, rng));
        c.extra_fields.push_back(MakeExtra("moment", 'I', 2, 3, n, rng));
        c.extra_fields.push_back(MakeExtra("timestamp", 'F', 8, 1, n, rng));
        c.extra_fields.push_back(MakeExtra("fpfh", 'F', 4, 33, n, rng));
        c.extra_fields.push_back(MakeExtra("object", 'I', 8, 1, n, rng));
        c.extra_fields.push_back(MakeExtra("category", 'U', 8, 2, n, rng));
    }
    c.SetUnorganized();
    if (fields & kOrganized) {
        c.width = 4;
        c.height = 3;
        c.points[1] = Eigen::Vector3f::Constant(kNaN);
        c.points[6] = Eigen::Vector3f::Constant(kNaN);
        c.points[11] = {kNaN, 1.0f, kNaN};
        if (c.HasNormals()) c.normals[6] = Eigen::Vector3f::Constant(kNaN);
        c.sensor_origin = {0.5f, -1.25f, 2.0f};
        c.sensor_orientation = Eigen::Quaternionf(0.0f, 1.0f, 0.0f, 0.0f);
    }
    return c;
}

const char* EncodingName(PcdEncoding e) {
    return e == PcdEncoding::kAscii ? "Ascii" : e == PcdEncoding::kBinary ? "Binary" : "Compressed";
}

/// The exception message of ReadPcd(path), which must throw E.
template <typename E>
std::string ReadError(const fs::path& path) {
    try {
        ReadPcd(path);
    } catch (const E& e) {
        return e.what();
    }
    ADD_FAILURE() << "ReadPcd(" << path << ") did not throw the expected exception";
    return {};
}

/// Checks that reading `path` throws FormatError naming the file and containing `what`.
void ExpectFormatError(const fs::path& path, const std::string& what) {
    EXPECT_THROW(ReadPcd(path), FormatError);
    const std::string msg = ReadError<FormatError>(path);
    EXPECT_NE(msg.find(path.string()), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << "expected '" << what << "' in: " << msg;
}

/// Minimal LZF stream made of literal runs (control byte = run length - 1, at most 32 bytes).
std::string LzfLiterals(const std::string& raw) {
    std::string out;
    for (std::size_t i = 0; i < raw.size(); i += 32) {
        const std::size_t len = std::min<std::size_t>(32, raw.size() - i);
        out.push_back(static_cast<char>(len - 1));
        out.append(raw, i, len);
    }
    return out;
}

std::string U32(std::uint32_t v) {
    std::string s(4, '\0');
    std::memcpy(s.data(), &v, 4);
    return s;
}
std::string F32(float v) { return U32(std::bit_cast<std::uint32_t>(v)); }

// ---------------------------------------------------------------------------------- round trip

class PcdRoundTrip : public ::testing::TestWithParam<PcdEncoding> {
  protected:
    PointCloud RoundTrip(const PointCloud& c) {
        const fs::path p = dir_ / "cloud.pcd";
        WritePcd(p, c, {.encoding = GetParam()});
        return ReadPcd(p);
    }
    std::string Header(const PointCloud& c) {
        const fs::path p = dir_ / "header.pcd";
        WritePcd(p, c, {.encoding = GetParam()});
        const std::string bytes = ReadBytes(p);
        return bytes.substr(0, bytes.find("DATA"));
    }
    test::TempDir dir_;
};

TEST_P(PcdRoundTrip, XyzOnly) {
    const PointCloud c = MakeCloud(0);
    ExpectSameCloud(RoundTrip(c), c);
    EXPECT_NE(Header(c).find("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"),
              std::string::npos);
}

TEST_P(PcdRoundTrip, OpaqueColorsAsRgb) {
    const PointCloud c = MakeCloud(kRgb);
    ExpectSameCloud(RoundTrip(c), c);
    // As PCL: rgb is F 4, except in ascii where the packed colour is printed as an integer.
    const std::string type = GetParam() == PcdEncoding::kAscii ? "F F F U" : "F F F F";
    EXPECT_NE(Header(c).find("FIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE " + type + "\n"),
              std::string::npos);
}

TEST_P(PcdRoundTrip, TranslucentColorsAsRgba) {
    const PointCloud c = MakeCloud(kRgbaAlpha);
    ExpectSameCloud(RoundTrip(c), c);
    EXPECT_NE(Header(c).find("FIELDS x y z rgba\nSIZE 4 4 4 4\nTYPE F F F U\n"), std::string::npos);
}

TEST_P(PcdRoundTrip, NormalsAndCurvature) {
    const PointCloud c = MakeCloud(kNormals);
    ExpectSameCloud(RoundTrip(c), c);
    EXPECT_NE(Header(c).find("FIELDS x y z normal_x normal_y normal_z curvature\n"),
              std::string::npos);
}

TEST_P(PcdRoundTrip, Labels) {
    const PointCloud c = MakeCloud(kLabels);
    ExpectSameCloud(RoundTrip(c), c);
}

TEST_P(PcdRoundTrip, IntensityAndConfidence) {
    const PointCloud c = MakeCloud(kIntensity);
    ExpectSameCloud(RoundTrip(c), c);
}

TEST_P(PcdRoundTrip, ExtraFieldsOfEveryShape) {
    const PointCloud c = MakeCloud(kExtras);
    ExpectSameCloud(RoundTrip(c), c);
    const std::string h = Header(c);
    EXPECT_NE(h.find("FIELDS x y z ring moment timestamp fpfh object category\n"
                     "SIZE 4 4 4 1 2 8 4 8 8\nTYPE F F F U I F F I U\nCOUNT 1 1 1 1 3 1 33 1 2\n"),
              std::string::npos)
        << h;
}

TEST_P(PcdRoundTrip, AllFieldsInDocumentedOrder) {
    const PointCloud c = MakeCloud(kRgbaAlpha | kNormals | kLabels | kIntensity | kExtras);
    ExpectSameCloud(RoundTrip(c), c);
    EXPECT_NE(Header(c).find("FIELDS x y z normal_x normal_y normal_z curvature rgba label "
                             "intensity confidence ring moment"),
              std::string::npos);
}

TEST_P(PcdRoundTrip, OrganizedWithNaNsAndViewpoint) {
    const PointCloud c = MakeCloud(kOrganized | kRgb | kNormals);
    const PointCloud r = RoundTrip(c);
    ExpectSameCloud(r, c);
    EXPECT_TRUE(r.IsOrganized());
    EXPECT_EQ(r.CountFinite(), 9u);
    EXPECT_TRUE(std::isnan(r.At(1, 0).x()));
    const std::string h = Header(c);
    EXPECT_NE(h.find("WIDTH 4\nHEIGHT 3\nVIEWPOINT 0.5 -1.25 2 0 1 0 0\nPOINTS 12\n"),
              std::string::npos)
        << h;
}

TEST_P(PcdRoundTrip, EmptyCloud) {
    PointCloud c;
    const PointCloud r = RoundTrip(c);
    EXPECT_TRUE(r.empty());
    EXPECT_EQ(r.width, 0u);
    EXPECT_EQ(r.height, 1u);
    c.colors = {};
    c.extra_fields.push_back({"ring", 'U', 2, 1, {}});
    const PointCloud r2 = RoundTrip(c);
    EXPECT_TRUE(r2.empty());
    ASSERT_EQ(r2.extra_fields.size(), 1u);
    EXPECT_EQ(r2.extra_fields[0].name, "ring");
}

TEST_P(PcdRoundTrip, IncompressibleData) {
    // Random bytes do not compress; the file must still be valid (PCL also stores such data
    // compressed) and tiny clouds too.
    std::mt19937 rng(9);
    PointCloud c = MakeCloud(0, 1000);
    c.extra_fields.push_back(MakeExtra("noise", 'U', 1, 64, c.size(), rng));
    ExpectSameCloud(RoundTrip(c), c);
    const PointCloud one = MakeCloud(0, 1);
    ExpectSameCloud(RoundTrip(one), one);
}

TEST_P(PcdRoundTrip, OverwritesExistingFile) {
    const PointCloud a = MakeCloud(kRgb, 50);
    const PointCloud b = MakeCloud(0, 3);
    ExpectSameCloud(RoundTrip(a), a);
    ExpectSameCloud(RoundTrip(b), b);
}

INSTANTIATE_TEST_SUITE_P(Encodings, PcdRoundTrip,
                         ::testing::Values(PcdEncoding::kAscii, PcdEncoding::kBinary,
                                           PcdEncoding::kBinaryCompressed),
                         [](const auto& param_info) { return EncodingName(param_info.param); });

// ------------------------------------------------------------------------ hand-written files

TEST(PcdRead, AsciiWithCommentsAndV06Header) {
    test::TempDir dir;
    const fs::path p = dir / "v06.pcd";
    // No VIEWPOINT, POINTS or COUNT; comments, tabs, CRLF and blank lines; nan in any case.
    WriteBytes(p,
               "# .PCD v.6 - Point Cloud Data file format\n"
               "VERSION .6\r\n"
               "FIELDS x y\tz rgb   # trailing comment\n"
               "\n"
               "SIZE 4 4 4 4\n"
               "TYPE F F F F\n"
               "WIDTH 3\n"
               "HEIGHT 1\n"
               "DATA ascii\n"
               "1.5 -2 3e-2 4278190335\r\n"
               "\n"
               "nan NaN -nan 0\n"
               "  +7\t8 9 4.2108e+06  \n");
    const PointCloud c = ReadPcd(p);
    ASSERT_EQ(c.size(), 3u);
    EXPECT_EQ(c.width, 3u);
    EXPECT_EQ(c.height, 1u);
    EXPECT_EQ(c.points[0], Eigen::Vector3f(1.5f, -2.0f, 0.03f));
    EXPECT_TRUE(std::isnan(c.points[1].x()) && std::isnan(c.points[1].y()) &&
                std::isnan(c.points[1].z()));
    EXPECT_EQ(c.points[2], Eigen::Vector3f(7, 8, 9));
    ASSERT_TRUE(c.HasColors());
    EXPECT_EQ(c.colors[0], (Color{0, 0, 255, 255}));
    // rgb with alpha byte 0 is an opaque colour.
    EXPECT_EQ(c.colors[1], (Color{0, 0, 0, 255}));
    // Older writers print the packed colour as a float.
    Color old = UnpackRgba(std::bit_cast<std::uint32_t>(4.2108e+06f));
    EXPECT_EQ(c.colors[2], old);
    EXPECT_EQ(c.sensor_origin, Eigen::Vector3f::Zero());
    EXPECT_EQ(c.sensor_orientation.coeffs(), Eigen::Quaternionf::Identity().coeffs());

    // Only POINTS, no WIDTH/HEIGHT: an unorganized cloud of that many points.
    WriteBytes(p, "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6\n");
    const PointCloud d = ReadPcd(p);
    ASSERT_EQ(d.size(), 2u);
    EXPECT_EQ(d.width, 2u);
    EXPECT_EQ(d.height, 1u);
    EXPECT_EQ(d.points[1], Eigen::Vector3f(4, 5, 6));
}

TEST(PcdRead, UnknownFieldsAreKeptAndKnownFieldsConverted) {
    test::TempDir dir;
    const fs::path p = dir / "mixed.pcd";
    WriteBytes(p,
               "VERSION 0.7\n"
               "FIELDS label x y z object category moment normal_x intensity\n"
               "SIZE 2 8 4 4 1 4 4 4 1\n"
               "TYPE U F F F I U F F U\n"
               "COUNT 1 1 1 1 1 1 3 1 1\n"
               "WIDTH 2\nHEIGHT 1\nVIEWPOINT 1 2 3 0.5 0.5 0.5 0.5\nPOINTS 2\nDATA ascii\n"
               "7 0.1 2 3 -5 4000000000 1 2 3 0.5 200\n"
               "65535 1e300 5 6 127 0 nan 0 0 0.25 0\n");
    std::vector<std::string> messages;
    SetLogSink([&](LogLevel, std::string_view m) { messages.emplace_back(m); });
    const LogLevel old_level = GetLogLevel();
    SetLogLevel(LogLevel::kDebug);
    const PointCloud c = ReadPcd(p);
    SetLogLevel(old_level);
    SetLogSink({});
    ASSERT_EQ(c.size(), 2u);
    EXPECT_EQ(c.labels, (std::vector<std::uint32_t>{7, 65535}));
    EXPECT_EQ(c.points[0].x(), static_cast<float>(0.1));
    EXPECT_TRUE(std::isinf(c.points[1].x()));  // double beyond float range
    EXPECT_EQ(c.intensity, (std::vector<float>{200.0f, 0.0f}));
    EXPECT_FALSE(c.HasNormals());  // normal_x alone is no normal
    ASSERT_EQ(c.extra_fields.size(), 4u);
    EXPECT_EQ(c.extra_fields[0].name, "object");
    EXPECT_EQ(c.extra_fields[0].type, 'I');
    EXPECT_EQ(c.extra_fields[0].data, (std::vector<std::uint8_t>{0xfb, 127}));
    const ExtraField* cat = c.FindExtraField("category");
    ASSERT_NE(cat, nullptr);
    std::uint32_t v = 0;
    std::memcpy(&v, cat->data.data(), 4);
    EXPECT_EQ(v, 4000000000u);
    const ExtraField* moment = c.FindExtraField("moment");
    ASSERT_NE(moment, nullptr);
    EXPECT_EQ(moment->count, 3u);
    float m[6];
    std::memcpy(m, moment->data.data(), sizeof(m));
    EXPECT_EQ(m[2], 3.0f);
    EXPECT_TRUE(std::isnan(m[3]));
    EXPECT_NE(c.FindExtraField("normal_x"), nullptr);
    EXPECT_EQ(c.sensor_origin, Eigen::Vector3f(1, 2, 3));
    EXPECT_EQ(c.sensor_orientation.w(), 0.5f);
    // One debug message for all unknown fields.
    int extra_messages = 0;
    for (const auto& msg : messages)
        extra_messages += msg.find("extra fields") != std::string::npos;
    EXPECT_EQ(extra_messages, 1);
}

TEST(PcdRead, BinaryAndCompressedWithPadding) {
    // Records x y z _ label where '_' is 4 bytes of padding, as PCL writes aligned point types.
    const std::string head =
        "VERSION 0.7\nFIELDS x y z _ label\nSIZE 4 4 4 1 4\nTYPE F F F U U\nCOUNT 1 1 1 4 1\n"
        "WIDTH 2\nHEIGHT 1\nPOINTS 2\n";
    std::string records;
    records += F32(1) + F32(2) + F32(3) + "PPPP" + U32(10);
    records += F32(4) + F32(5) + F32(kNaN) + "PPPP" + U32(20);
    // Compressed data leaves the padding out (PCL's layout): planes x, y, z, label.
    std::string planes = F32(1) + F32(4) + F32(2) + F32(5) + F32(3) + F32(kNaN) + U32(10) + U32(20);
    const std::string lzf = LzfLiterals(planes);
    test::TempDir dir;
    WriteBytes(dir / "binary.pcd", head + "DATA binary\n" + records);
    WriteBytes(dir / "compressed.pcd",
               head + "DATA binary_compressed\n" + U32(lzf.size()) + U32(planes.size()) + lzf);
    // In ascii, PCL leaves padding out; values for it are accepted too.
    WriteBytes(dir / "ascii.pcd", head + "DATA ascii\n1 2 3 10\n4 5 nan 0 0 0 0 20\n");
    for (const char* name : {"binary.pcd", "compressed.pcd", "ascii.pcd"}) {
        SCOPED_TRACE(name);
        const PointCloud c = ReadPcd(dir / name);
        ASSERT_EQ(c.size(), 2u);
        EXPECT_EQ(c.points[0], Eigen::Vector3f(1, 2, 3));
        EXPECT_EQ(c.points[1].head<2>(), Eigen::Vector2f(4, 5));
        EXPECT_TRUE(std::isnan(c.points[1].z()));
        EXPECT_EQ(c.labels, (std::vector<std::uint32_t>{10, 20}));
        EXPECT_TRUE(c.extra_fields.empty());
    }
}

// --------------------------------------------------------------------------------- bad input

class PcdBadInput : public ::testing::Test {
  protected:
    fs::path File(const std::string& name, const std::string& bytes) {
        const fs::path p = dir_ / name;
        WriteBytes(p, bytes);
        return p;
    }
    /// A valid file of the given encoding, as bytes.
    std::string Valid(PcdEncoding e, std::size_t n = 500) {
        const fs::path p = dir_ / "valid.pcd";
        WritePcd(p, MakeCloud(kRgb, n), {.encoding = e});
        return ReadBytes(p);
    }
    test::TempDir dir_;
};

const std::string kXyzHeader =
    "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
    "POINTS 2\n";

TEST_F(PcdBadInput, MissingFileAndDirectory) {
    const fs::path missing = dir_ / "missing.pcd";
    EXPECT_THROW(ReadPcd(missing), IoError);
    EXPECT_NE(ReadError<IoError>(missing).find(missing.string()), std::string::npos);
    EXPECT_THROW(ReadPcd(dir_.path()), IoError);
    EXPECT_NE(ReadError<IoError>(dir_.path()).find("directory"), std::string::npos);
}

TEST_F(PcdBadInput, TruncatedBinaryData) {
    const std::string bytes = Valid(PcdEncoding::kBinary);
    ExpectFormatError(File("cut.pcd", bytes.substr(0, bytes.size() - 7)),
                      "DATA section truncated: expected 8000 bytes, got 7993");
}

TEST_F(PcdBadInput, TruncatedCompressedData) {
    const std::string bytes = Valid(PcdEncoding::kBinaryCompressed);
    ExpectFormatError(File("cut.pcd", bytes.substr(0, bytes.size() - 100)), "truncated");
    const std::size_t data = bytes.find("binary_compressed\n") + 18;
    ExpectFormatError(File("cut_sizes.pcd", bytes.substr(0, data + 5)), "truncated");
}

TEST_F(PcdBadInput, CorruptCompressedSizes) {
    const std::string bytes = Valid(PcdEncoding::kBinaryCompressed);
    const std::size_t data = bytes.find("binary_compressed\n") + 18;
    std::string wrong_uncompressed = bytes;
    wrong_uncompressed.replace(data + 4, 4, U32(7999));
    ExpectFormatError(File("u.pcd", wrong_uncompressed), "corrupt compressed header");
    std::string huge_compressed = bytes;
    huge_compressed.replace(data, 4, U32(0xfffffff0u));
    ExpectFormatError(File("c.pcd", huge_compressed), "truncated");
    std::string tiny_compressed = bytes;
    tiny_compressed.replace(data, 4, U32(3));
    ExpectFormatError(File("t.pcd", tiny_compressed), "corrupt compressed");
    std::string garbage = bytes;
    for (std::size_t i = data + 8; i < garbage.size(); ++i) garbage[i] = static_cast<char>(0xff);
    ExpectFormatError(File("g.pcd", garbage), "corrupt compressed data");
}

TEST_F(PcdBadInput, HeaderFieldCountMismatch) {
    ExpectFormatError(
        File("size.pcd", "FIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n1 2 3\n"),
        "FIELDS has 3 entries, SIZE has 2");
    ExpectFormatError(
        File("count.pcd",
             "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1 1\nWIDTH 1\nDATA ascii\n"),
        "COUNT has 4");
    ExpectFormatError(File("nosize.pcd", "FIELDS x y z\nTYPE F F F\nWIDTH 1\nDATA ascii\n1 2 3\n"),
                      "no SIZE");
}

TEST_F(PcdBadInput, PointsMismatch) {
    ExpectFormatError(File("points.pcd",
                           "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 640\n"
                           "HEIGHT 480\nPOINTS 1200\nDATA binary\n"),
                      "POINTS 1200 does not match WIDTH*HEIGHT");
}

TEST_F(PcdBadInput, UnsupportedTypeSize) {
    ExpectFormatError(
        File("f2.pcd", "FIELDS x y z\nSIZE 2 4 4\nTYPE F F F\nWIDTH 1\nDATA binary\n"),
        "unsupported TYPE/SIZE combination F 2");
    ExpectFormatError(
        File("u3.pcd", "FIELDS x y z label\nSIZE 4 4 4 3\nTYPE F F F U\nWIDTH 1\nDATA binary\n"),
        "unsupported TYPE/SIZE combination U 3");
    ExpectFormatError(File("q.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F Q\nWIDTH 1\nDATA binary\n"),
                      "field 'z'");
}

TEST_F(PcdBadInput, AsciiTokenCounts) {
    ExpectFormatError(File("few.pcd", kXyzHeader + "DATA ascii\n1 2 3\n4 5\n"),
                      "line 11: expected 3 values, got 2");
    ExpectFormatError(File("many.pcd", kXyzHeader + "DATA ascii\n1 2 3 4\n"),
                      "line 10: expected 3 values, got 4");
    ExpectFormatError(File("short.pcd", kXyzHeader + "DATA ascii\n1 2 3\n"),
                      "expected 2 points, got 1");
    ExpectFormatError(File("word.pcd", kXyzHeader + "DATA ascii\n1 2 3\n4 five 6\n"),
                      "line 11: cannot parse 'five'");
}

TEST_F(PcdBadInput, NoXField) {
    ExpectFormatError(File("nox.pcd",
                           "FIELDS y z rgb\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n"
                           "1 2 3\n"),
                      "no x/y/z fields");
}

TEST_F(PcdBadInput, GarbageFiles) {
    std::string binary(4096, '\0');
    std::mt19937 rng(5);
    for (auto& ch : binary) ch = static_cast<char>(rng());
    ExpectFormatError(File("random.pcd", binary), "not a PCD file");
    ExpectFormatError(File("text.pcd", "hello world\nthis is no point cloud\n"), "not a PCD file");
    ExpectFormatError(File("empty.pcd", ""), "no DATA line");
    ExpectFormatError(File("nodata.pcd", kXyzHeader), "no DATA line");
    ExpectFormatError(File("dataline.pcd", kXyzHeader + "1 2 3\n4 5 6\n"),
                      "line 9: '1' in the header (no DATA line before it?)");
    ExpectFormatError(File("enc.pcd", kXyzHeader + "DATA zip\n"), "unknown DATA encoding 'zip'");
    ExpectFormatError(
        File("width.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH -3\nDATA ascii\n"),
        "bad WIDTH value '-3'");
    ExpectFormatError(File("vp.pcd", kXyzHeader + "VIEWPOINT 0 0 0 1\nDATA ascii\n"),
                      "VIEWPOINT needs 7 values");
    // A header claiming billions of points over a few bytes of data.
    ExpectFormatError(File("huge.pcd",
                           "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 100000\n"
                           "HEIGHT 100000\nDATA ascii\n1 2 3\n"),
                      "truncated");
}

TEST_F(PcdBadInput, FailedWriteLeavesExistingFileUntouched) {
    const fs::path p = dir_ / "keep.pcd";
    WritePcd(p, MakeCloud(kRgb, 20));
    const std::string before = ReadBytes(p);
    PointCloud bad = MakeCloud(kNormals, 20);
    bad.normals.pop_back();
    EXPECT_THROW(WritePcd(p, bad), DataError);
    PointCloud bad_extra = MakeCloud(0, 20);
    bad_extra.extra_fields.push_back({"half", 'F', 2, 1, std::vector<std::uint8_t>(40)});
    EXPECT_THROW(WritePcd(p, bad_extra), DataError);
    bad_extra.extra_fields.back() = {"two words", 'F', 4, 1, std::vector<std::uint8_t>(80)};
    EXPECT_THROW(WritePcd(p, bad_extra), DataError);
    EXPECT_EQ(ReadBytes(p), before);
    EXPECT_EQ(std::distance(fs::directory_iterator(dir_.path()), fs::directory_iterator()), 1);
    EXPECT_THROW(WritePcd(dir_ / "no" / "such" / "folder.pcd", MakeCloud(0)), IoError);
}

// ------------------------------------------------------------------------------- shared data

TEST(PcdSharedData, ScansHaveDocumentedContent) {
    if (!test::HasSharedData()) GTEST_SKIP() << "shared data not available";
    struct Scan {
        const char* name;
        std::size_t points, finite;
        bool organized, colors, normals;
    };
    const Scan scans[] = {
        {"table_scene_mug_stereo_textured.pcd", 307200, 209280, true, true, false},
        {"milk_cartoon_all_small_clorox.pcd", 307200, 241407, true, true, false},
        {"milk.pcd", 12575, 12575, false, true, false},
        {"region_growing_tutorial.pcd", 108104, 108104, false, true, false},
        {"capture0001.pcd", 307200, 249647, true, false, false},
        {"capture0002.pcd", 307200, 249931, true, false, false},
        {"bunny.pcd", 397, 397, false, false, false},
        {"bun0.pcd", 397, 397, false, false, true},
        {"bun4.pcd", 361, 361, false, false, false},
    };
    for (const auto& s : scans) {
        SCOPED_TRACE(s.name);
        const PointCloud c = ReadPcd(test::SharedData("scans") / s.name);
        EXPECT_EQ(c.size(), s.points);
        EXPECT_EQ(c.CountFinite(), s.finite);
        EXPECT_EQ(c.IsOrganized(), s.organized);
        if (s.organized) {
            EXPECT_EQ(c.width, 640u);
            EXPECT_EQ(c.height, 480u);
        }
        EXPECT_EQ(c.HasColors(), s.colors);
        EXPECT_EQ(c.HasNormals(), s.normals);
        EXPECT_EQ(c.HasCurvature(), s.normals);
        EXPECT_FALSE(c.HasLabels());
        EXPECT_TRUE(c.extra_fields.empty());
    }
    const PointCloud mug = ReadPcd(test::SharedData("scans/table_scene_mug_stereo_textured.pcd"));
    Eigen::Vector3f lo, hi;
    ASSERT_TRUE(ComputeBounds(mug, lo, hi));
    EXPECT_NEAR(lo.z(), 0.69f, 0.01f);
    EXPECT_NEAR(hi.z(), 2.59f, 0.01f);
    EXPECT_EQ(mug.sensor_orientation.coeffs(), Eigen::Quaternionf(0, 1, 0, 0).coeffs());
    // A real scan survives our own compressed writer bit for bit.
    test::TempDir dir;
    WritePcd(dir / "mug.pcd", mug);
    ExpectSameCloud(ReadPcd(dir / "mug.pcd"), mug);
}

TEST(PcdSharedData, MosdLabelsMarkInvalidPoints) {
    if (!test::HasSharedData()) GTEST_SKIP() << "shared data not available";
    for (int k = 0; k < 45; ++k) {
        const std::string name = "learn" + std::to_string(k) + ".pcd";
        SCOPED_TRACE(name);
        const PointCloud c = ReadPcd(test::SharedData("scans/mosd-learn") / name);
        ASSERT_EQ(c.size(), 307200u);
        EXPECT_TRUE(c.IsOrganized());
        ASSERT_TRUE(c.HasLabels());
        ASSERT_TRUE(c.HasColors());
        std::size_t mismatched = 0, objects = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            mismatched += (c.labels[i] == 0) != std::isnan(c.points[i].z());
            objects += c.labels[i] >= 20;
        }
        EXPECT_EQ(mismatched, 0u);
        EXPECT_GT(objects, 0u);
    }
}

}  // namespace
}  // namespace multicue
