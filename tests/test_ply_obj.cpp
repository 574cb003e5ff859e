// PLY reader/writer and OBJ reader: round trips, hand-made files, bad input and the shared meshes.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/obj.hpp"
#include "multicue/io/ply.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

using io::PlyEncoding;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

void WriteBytes(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// Bit-identical floats; any NaN equals any NaN (text has no NaN payloads).
bool SameFloat(float a, float b) {
    if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
    return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

void ExpectSameVectors(const std::vector<Eigen::Vector3f>& a,
                       const std::vector<Eigen::Vector3f>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            ASSERT_TRUE(SameFloat(a[i][k], b[i][k]))
                << "entry " << i << "[" << k << "]: " << a[i][k] << " vs " << b[i][k];
        }
    }
}

void ExpectSameFloats(const std::vector<float>& a, const std::vector<float>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        ASSERT_TRUE(SameFloat(a[i], b[i])) << "entry " << i << ": " << a[i] << " vs " << b[i];
    }
}

/// Points with awkward values: signed zero, denormals, extremes, NaN, infinity, shortest-repr
/// edge cases.
PointCloud AwkwardCloud() {
    PointCloud c = test::RandomCloud(200, 7, 100.0f);
    c.points[0] = {-0.0f, std::numeric_limits<float>::denorm_min(), 1e-38f};
    c.points[1] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest(), 0.1f};
    c.points[2] = {kNaN, kNaN, kNaN};
    c.points[3] = {kInf, -kInf, 16777217.0f};
    c.points[4] = {1.0f / 3.0f, 2e-7f, 123456.789f};
    return c;
}

PointCloud FullCloud(std::size_t n) {
    PointCloud c = test::RandomCloud(n, 3);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (std::size_t i = 0; i < n; ++i) {
        c.normals.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized());
        c.colors.push_back(Color{static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(3 * i),
                                 static_cast<std::uint8_t>(255 - i), 255});
        c.labels.push_back(static_cast<std::uint32_t>(i * 977));
        c.intensity.push_back(u(rng) * 1000.0f);
        c.confidence.push_back(u(rng));
        c.curvature.push_back(std::abs(u(rng)) / 3.0f);
    }
    if (n > 2) {
        c.normals[1] = Eigen::Vector3f::Constant(kNaN);
        c.labels[2] = 0xffffffffu;
    }
    return c;
}

std::string Header(const std::filesystem::path& path) {
    const std::string bytes = io::ReadFileBytes(path);
    return bytes.substr(0, bytes.find("end_header"));
}

class PlyEncodings : public ::testing::TestWithParam<PlyEncoding> {};

INSTANTIATE_TEST_SUITE_P(All, PlyEncodings,
                         ::testing::Values(PlyEncoding::kAscii, PlyEncoding::kBinaryLittleEndian,
                                           PlyEncoding::kBinaryBigEndian),
                         [](const auto& param_info) {
                             switch (param_info.param) {
                                 case PlyEncoding::kAscii:
                                     return std::string("Ascii");
                                 case PlyEncoding::kBinaryLittleEndian:
                                     return std::string("BinaryLittleEndian");
                                 default:
                                     return std::string("BinaryBigEndian");
                             }
                         });

TEST_P(PlyEncodings, CloudXyzRoundTripsBitExact) {
    test::TempDir dir;
    const PointCloud c = AwkwardCloud();
    io::WritePly(dir / "c.ply", c, {.encoding = GetParam()});
    const PointCloud r = io::ReadPly(dir / "c.ply");
    ExpectSameVectors(c.points, r.points);
    EXPECT_EQ(r.width, c.size());
    EXPECT_EQ(r.height, 1u);
    EXPECT_FALSE(r.HasNormals() || r.HasColors() || r.HasLabels() || r.HasIntensity() ||
                 r.HasConfidence() || r.HasCurvature());
    EXPECT_TRUE(r.extra_fields.empty());
}

TEST_P(PlyEncodings, CloudWithAllFieldsRoundTrips) {
    test::TempDir dir;
    const PointCloud c = FullCloud(300);
    io::WritePly(dir / "c.ply", c, {.encoding = GetParam()});
    EXPECT_EQ(Header(dir / "c.ply").find("alpha"), std::string::npos);  // all opaque
    const PointCloud r = io::ReadPly(dir / "c.ply");
    ExpectSameVectors(c.points, r.points);
    ExpectSameVectors(c.normals, r.normals);
    EXPECT_EQ(c.colors, r.colors);
    EXPECT_EQ(c.labels, r.labels);
    ExpectSameFloats(c.intensity, r.intensity);
    ExpectSameFloats(c.confidence, r.confidence);
    ExpectSameFloats(c.curvature, r.curvature);
    EXPECT_TRUE(r.extra_fields.empty());
}

TEST_P(PlyEncodings, ColorsWithAlphaRoundTrip) {
    test::TempDir dir;
    PointCloud c = test::RandomCloud(50);
    for (std::size_t i = 0; i < c.size(); ++i) {
        c.colors.push_back(
            Color{static_cast<std::uint8_t>(i), 7, 200, static_cast<std::uint8_t>(i * 5)});
    }
    io::WritePly(dir / "c.ply", c, {.encoding = GetParam()});
    EXPECT_NE(Header(dir / "c.ply").find("property uchar alpha"), std::string::npos);
    const PointCloud r = io::ReadPly(dir / "c.ply");
    EXPECT_EQ(c.colors, r.colors);
}

TEST_P(PlyEncodings, ExtraFieldsRoundTripAndCountAboveOneIsSkipped) {
    test::TempDir dir;
    PointCloud c = test::RandomCloud(20);
    const std::pair<char, std::uint8_t> kinds[] = {{'I', 1}, {'U', 1}, {'I', 2}, {'U', 2},
                                                   {'I', 4}, {'U', 4}, {'F', 4}, {'F', 8}};
    std::mt19937 rng(11);
    for (const auto& [type, size] : kinds) {
        ExtraField f{fmt::format("e_{}{}", type, size), type, size, 1, {}};
        f.data.resize(c.size() * size);
        for (auto& b : f.data) b = static_cast<std::uint8_t>(rng());
        if (type == 'F') {  // finite floats with random bits
            for (std::size_t i = 0; i < c.size(); ++i) {
                if (size == 4) {
                    const float v = static_cast<float>(rng()) * 1e-3f - 1e6f;
                    std::memcpy(f.data.data() + i * 4, &v, 4);
                } else {
                    const double v = static_cast<double>(rng()) / 7.0 - 3e8;
                    std::memcpy(f.data.data() + i * 8, &v, 8);
                }
            }
        }
        c.extra_fields.push_back(f);
    }
    ExtraField vec{"histogram", 'F', 4, 3, std::vector<std::uint8_t>(c.size() * 12, 0)};
    c.extra_fields.push_back(vec);

    std::vector<std::string> warnings;
    SetLogSink([&](LogLevel, std::string_view m) { warnings.emplace_back(m); });
    io::WritePly(dir / "c.ply", c, {.encoding = GetParam()});
    SetLogSink({});
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("histogram"), std::string::npos);

    const PointCloud r = io::ReadPly(dir / "c.ply");
    ASSERT_EQ(r.extra_fields.size(), 8u);
    for (std::size_t k = 0; k < 8; ++k) {
        const ExtraField& a = c.extra_fields[k];
        const ExtraField& b = r.extra_fields[k];
        EXPECT_EQ(a.name, b.name);
        EXPECT_EQ(a.type, b.type) << a.name;
        EXPECT_EQ(a.size, b.size) << a.name;
        EXPECT_EQ(b.count, 1u);
        EXPECT_EQ(a.data, b.data) << a.name;
    }
    EXPECT_EQ(r.FindExtraField("histogram"), nullptr);
}

TEST_P(PlyEncodings, MeshRoundTripsWithNormalsColorsLabels) {
    test::TempDir dir;
    TriangleMesh m;
    const PointCloud c = FullCloud(40);
    m.vertices = c.points;
    m.vertex_normals = c.normals;
    m.vertex_colors = c.colors;
    m.vertex_colors[3].a = 17;
    m.vertex_labels = c.labels;
    for (std::uint32_t i = 0; i + 2 < 40; ++i) m.triangles.emplace_back(i, i + 1, i + 2);
    io::WritePlyMesh(dir / "m.ply", m, {.encoding = GetParam()});
    const TriangleMesh r = io::ReadPlyMesh(dir / "m.ply");
    ExpectSameVectors(m.vertices, r.vertices);
    ExpectSameVectors(m.vertex_normals, r.vertex_normals);
    EXPECT_EQ(m.vertex_colors, r.vertex_colors);
    EXPECT_EQ(m.vertex_labels, r.vertex_labels);
    EXPECT_EQ(m.triangles, r.triangles);

    // The same file read as a cloud gives the vertices.
    const PointCloud v = io::ReadPly(dir / "m.ply");
    ExpectSameVectors(m.vertices, v.points);
    EXPECT_EQ(m.vertex_labels, v.labels);
}

TEST_P(PlyEncodings, EmptyCloudAndEmptyMesh) {
    test::TempDir dir;
    io::WritePly(dir / "c.ply", PointCloud{}, {.encoding = GetParam()});
    const PointCloud r = io::ReadPly(dir / "c.ply");
    EXPECT_TRUE(r.empty());
    EXPECT_EQ(r.width, 0u);
    io::WritePlyMesh(dir / "m.ply", TriangleMesh{}, {.encoding = GetParam()});
    const TriangleMesh m = io::ReadPlyMesh(dir / "m.ply");
    EXPECT_TRUE(m.empty());
    EXPECT_TRUE(m.triangles.empty());
}

/// Appends a value in big-endian byte order.
template <typename T>
void PutBigEndian(std::string& s, T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if constexpr (std::endian::native == std::endian::little) std::reverse(b, b + sizeof(T));
    s.append(b, sizeof(T));
}

TEST(Ply, HandMadeBigEndianFileIsSwapped) {
    test::TempDir dir;
    std::string s =
        "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty double z\nproperty uchar red\nproperty uchar green\n"
        "property uchar blue\nproperty ushort label\nproperty int16 temperature\n"
        "element face 1\nproperty list ushort uint vertex_indices\nend_header\n";
    const float xy[3][2] = {{1.5f, -2.25f}, {1e-3f, 7.0f}, {-0.0f, 3.0e8f}};
    const double z[3] = {0.1, -1e100, 42.0};
    for (int i = 0; i < 3; ++i) {
        PutBigEndian(s, xy[i][0]);
        PutBigEndian(s, xy[i][1]);
        PutBigEndian(s, z[i]);
        s += static_cast<char>(10 * i);
        s += static_cast<char>(20 * i);
        s += static_cast<char>(30 * i);
        PutBigEndian(s, static_cast<std::uint16_t>(1000 + i));
        PutBigEndian(s, static_cast<std::int16_t>(-300 * i));
    }
    PutBigEndian(s, std::uint16_t{3});
    for (std::uint32_t i : {2u, 0u, 1u}) PutBigEndian(s, i);
    WriteBytes(dir / "be.ply", s);

    const PointCloud c = io::ReadPly(dir / "be.ply");
    ASSERT_EQ(c.size(), 3u);
    for (int i = 0; i < 3; ++i) {
        EXPECT_TRUE(SameFloat(c.points[i].x(), xy[i][0]));
        EXPECT_TRUE(SameFloat(c.points[i].y(), xy[i][1]));
        EXPECT_TRUE(SameFloat(c.points[i].z(), static_cast<float>(z[i])));
        EXPECT_EQ(c.colors[i],
                  (Color{static_cast<std::uint8_t>(10 * i), static_cast<std::uint8_t>(20 * i),
                         static_cast<std::uint8_t>(30 * i), 255}));
        EXPECT_EQ(c.labels[i], 1000u + i);
    }
    const ExtraField* t = c.FindExtraField("temperature");
    ASSERT_NE(t, nullptr);
    EXPECT_EQ(t->type, 'I');
    EXPECT_EQ(t->size, 2);
    std::int16_t t2 = 0;
    std::memcpy(&t2, t->data.data() + 4, 2);
    EXPECT_EQ(t2, -600);

    const TriangleMesh m = io::ReadPlyMesh(dir / "be.ply");
    ASSERT_EQ(m.triangles.size(), 1u);
    EXPECT_EQ(m.triangles[0], Triangle(2, 0, 1));
}

/// A file whose first element ("material") has lists and scalars of several types, then vertices
/// with a skipped list property, then faces with a texcoord list before the indices.
std::string ElementsBeforeVertexAscii() {
    return "ply\nformat ascii 1.0\ncomment test\nobj_info made by hand\n"
           "element material 2\nproperty list uchar float params\nproperty uchar id\n"
           "property list int short ids\n"
           "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
           "property list uchar int neighbours\nproperty float confidence\n"
           "element face 2\nproperty list uchar float texcoord\n"
           "property list uint int vertex_index\nproperty uchar flags\n"
           "end_header\n"
           "3 0.5 0.25 0.125 7 2 -1 -2\n"
           "0 8 0\n"
           "0 0 0 2 1 2 0.5\n"
           "1 0 0 0 0.25\n"
           "1 1 0 1 3 0.125\n"
           "0 1 0 0 1\n"
           "6 0 0 1 0 1 1 3 0 1 2 9\n"
           "0 3 0 2 3 9\n";
}

TEST(Ply, ElementWithListsBeforeVertexAsciiAndBinary) {
    test::TempDir dir;
    WriteBytes(dir / "a.ply", ElementsBeforeVertexAscii());

    // The same content in binary little endian.
    std::string b =
        "ply\nformat binary_little_endian 1.0\n"
        "element material 2\nproperty list uchar float params\nproperty uchar id\n"
        "property list int short ids\n"
        "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        "property list uchar int neighbours\nproperty float confidence\n"
        "element face 2\nproperty list uchar float texcoord\n"
        "property list uint int vertex_index\nproperty uchar flags\n"
        "end_header\n";
    auto put = [&b](auto v) { b.append(reinterpret_cast<const char*>(&v), sizeof(v)); };
    put(std::uint8_t{3}), put(0.5f), put(0.25f), put(0.125f), put(std::uint8_t{7});
    put(std::int32_t{2}), put(std::int16_t{-1}), put(std::int16_t{-2});
    put(std::uint8_t{0}), put(std::uint8_t{8}), put(std::int32_t{0});
    const float xyz[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const std::vector<std::vector<std::int32_t>> nb = {{1, 2}, {}, {3}, {}};
    const float conf[4] = {0.5f, 0.25f, 0.125f, 1.0f};
    for (int i = 0; i < 4; ++i) {
        put(xyz[i][0]), put(xyz[i][1]), put(xyz[i][2]);
        put(static_cast<std::uint8_t>(nb[i].size()));
        for (auto k : nb[i]) put(k);
        put(conf[i]);
    }
    put(std::uint8_t{6});
    for (float t : {0.f, 0.f, 1.f, 0.f, 1.f, 1.f}) put(t);
    put(std::uint32_t{3}), put(std::int32_t{0}), put(std::int32_t{1}), put(std::int32_t{2});
    put(std::uint8_t{9});
    put(std::uint8_t{0});
    put(std::uint32_t{3}), put(std::int32_t{0}), put(std::int32_t{2}), put(std::int32_t{3});
    put(std::uint8_t{9});
    WriteBytes(dir / "b.ply", b);

    for (const char* name : {"a.ply", "b.ply"}) {
        SCOPED_TRACE(name);
        const TriangleMesh m = io::ReadPlyMesh(dir / name);
        ASSERT_EQ(m.vertices.size(), 4u);
        EXPECT_EQ(m.vertices[2], Eigen::Vector3f(1, 1, 0));
        ASSERT_EQ(m.triangles.size(), 2u);
        EXPECT_EQ(m.triangles[0], Triangle(0, 1, 2));
        EXPECT_EQ(m.triangles[1], Triangle(0, 2, 3));
        const PointCloud c = io::ReadPly(dir / name);
        ASSERT_EQ(c.size(), 4u);
        EXPECT_EQ(c.confidence, (std::vector<float>{0.5f, 0.25f, 0.125f, 1.0f}));
        EXPECT_TRUE(c.extra_fields.empty());  // the list property is not kept
    }
}

TEST(Ply, PolygonsAreFanTriangulated) {
    test::TempDir dir;
    WriteBytes(dir / "q.ply",
               "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
               "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
               "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2 1 0\n"
               "4 0 1 2 3\n5 1 4 5 2 3\n");
    const TriangleMesh m = io::ReadPlyMesh(dir / "q.ply");
    ASSERT_EQ(m.triangles.size(), 5u);
    EXPECT_EQ(m.triangles[0], Triangle(0, 1, 2));
    EXPECT_EQ(m.triangles[1], Triangle(0, 2, 3));
    EXPECT_EQ(m.triangles[2], Triangle(1, 4, 5));
    EXPECT_EQ(m.triangles[3], Triangle(1, 5, 2));
    EXPECT_EQ(m.triangles[4], Triangle(1, 2, 3));
}

TEST(Ply, AlternativeNamesFloatColoursAndSpecialValues) {
    test::TempDir dir;
    WriteBytes(dir / "n.ply",
               "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty double x\r\n"
               "property double y\r\nproperty double z\r\nproperty float normal_x\r\n"
               "property float normal_y\r\nproperty float normal_z\r\nproperty float r\r\n"
               "property float g\r\nproperty float b\r\nproperty int label\r\n"
               "property intensity float   { legacy order with a comment }\r\nend_header\r\n"
               "1 2 3 0 0 1 1.0 0.5 0 -1 nan\r\n"
               "+4 5e0 6 NaN inf -inf 0 0 1 7 Inf\r\n"
               "1e-60 0 0 0 0 0 0 0 2.0 3.0 -NaN\r\n");
    const PointCloud c = io::ReadPly(dir / "n.ply");
    ASSERT_EQ(c.size(), 3u);
    EXPECT_EQ(c.points[1], Eigen::Vector3f(4, 5, 6));
    EXPECT_EQ(c.points[2].x(), 0.0f);  // underflows
    ASSERT_TRUE(c.HasNormals());
    EXPECT_TRUE(std::isnan(c.normals[1].x()));
    EXPECT_EQ(c.normals[1].y(), kInf);
    EXPECT_EQ(c.normals[1].z(), -kInf);
    ASSERT_TRUE(c.HasColors());
    EXPECT_EQ(c.colors[0], (Color{255, 128, 0, 255}));
    EXPECT_EQ(c.colors[2], (Color{0, 0, 255, 255}));  // clamped
    EXPECT_EQ(c.labels, (std::vector<std::uint32_t>{0xffffffffu, 7, 3}));
    ASSERT_TRUE(c.HasIntensity());
    EXPECT_TRUE(std::isnan(c.intensity[0]));
    EXPECT_EQ(c.intensity[1], kInf);
}

TEST(Ply, ErrorsNameTheFile) {
    test::TempDir dir;
    auto expect_error = [&](const std::string& name, const std::string& content,
                            const std::string& part) {
        SCOPED_TRACE(name);
        WriteBytes(dir / name, content);
        try {
            (void)io::ReadPlyMesh(dir / name);
            ADD_FAILURE() << "no exception";
        } catch (const FormatError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(name), std::string::npos) << what;
            EXPECT_NE(what.find(part), std::string::npos) << what;
            EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        }
    };
    const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
    expect_error("magic.ply", "plx\nformat ascii 1.0\nend_header\n", "not a PLY file");
    expect_error("format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n",
                 "line 2: unknown format 'binary_middle_endian'");
    expect_error("version.ply", "ply\nformat ascii 2.0\nend_header\n", "version");
    expect_error("noformat.ply", "ply\nelement vertex 0\n" + xyz + "end_header\n", "format");
    expect_error("early.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
                 "line 3: property before any element");
    expect_error("noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz + "0 0 0\n",
                 "line 7: data before end_header");
    expect_error("eof.ply", "ply\nformat ascii 1.0\nelement vertex 0\n" + xyz, "no end_header");
    expect_error("type.ply",
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float32 x\n"
                 "property quad y\nproperty float z\nend_header\n0 0 0\n",
                 "line 5: unknown type 'quad'");
    expect_error("count.ply", "ply\nformat ascii 1.0\nelement vertex many\nend_header\n",
                 "bad element count");
    expect_error("listcount.ply",
                 "ply\nformat ascii 1.0\nelement vertex 0\n" + xyz +
                     "element face 0\nproperty list float int vertex_indices\nend_header\n",
                 "not an integer type");
    expect_error("keyword.ply", "ply\nformat ascii 1.0\nelemnt vertex 0\nend_header\n",
                 "unknown header keyword 'elemnt'");
    expect_error("nox.ply",
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nproperty float z\n"
                 "end_header\n0 0\n",
                 "no 'x' property");
    expect_error("novertex.ply", "ply\nformat ascii 1.0\nend_header\n", "no vertex element");
    expect_error(
        "number.ply",
        "ply\nformat ascii 1.0\nelement vertex 2\n" + xyz + "end_header\n0 0 0\n0 zero 0\n",
        "line 9: bad float value 'zero'");
    expect_error("range.ply",
                 "ply\nformat ascii 1.0\nelement vertex 3\n" + xyz +
                     "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
                     "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 900\n",
                 "line 14: face 1 refers to vertex 900 of 3");
    expect_error("negative.ply",
                 "ply\nformat ascii 1.0\nelement vertex 3\n" + xyz +
                     "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                     "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",
                 "refers to vertex -1 of 3");
    expect_error("long.ply",
                 "ply\nformat ascii 1.0\nelement vertex 2\n" + xyz + "end_header\n0 0 0 0\n1 1 1\n",
                 "line 8: more values than element 'vertex' has properties");
    expect_error("short.ply",
                 "ply\nformat ascii 1.0\nelement vertex 3\n" + xyz + "end_header\n0 0 0\n1 0 0\n",
                 "truncated");

    // Binary: truncated vertex data, truncated list data, out-of-range index.
    const std::string bin_header = "ply\nformat binary_little_endian 1.0\nelement vertex 2\n" +
                                   xyz +
                                   "element face 1\nproperty list uchar int vertex_indices\n"
                                   "end_header\n";
    std::string bin(bin_header);
    for (int i = 0; i < 6; ++i) {
        const float f = static_cast<float>(i);
        bin.append(reinterpret_cast<const char*>(&f), 4);
    }
    bin += static_cast<char>(3);
    for (std::int32_t i : {0, 1, 2}) bin.append(reinterpret_cast<const char*>(&i), 4);
    expect_error("trunc_vertex.ply", bin.substr(0, bin_header.size() + 10), "truncated");
    expect_error("trunc_list.ply", bin.substr(0, bin.size() - 3), "truncated");
    expect_error("bin_range.ply", bin, "face 0 refers to vertex 2 of 2");
}

TEST(Ply, MissingFileIsIoError) {
    test::TempDir dir;
    try {
        (void)io::ReadPly(dir / "missing.ply");
        FAIL() << "no exception";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("missing.ply"), std::string::npos);
    }
    EXPECT_THROW((void)io::ReadPlyMesh(dir / "missing.ply"), IoError);
    EXPECT_THROW((void)io::ReadObj(dir / "missing.obj"), IoError);
}

TEST(Ply, FailedWriteLeavesExistingFileUntouched) {
    test::TempDir dir;
    const auto path = dir / "keep.ply";
    io::WritePly(path, FullCloud(10), {.encoding = PlyEncoding::kAscii});
    const std::string before = io::ReadFileBytes(path);

    PointCloud bad = FullCloud(10);
    bad.normals.pop_back();
    EXPECT_THROW(io::WritePly(path, bad), DataError);
    TriangleMesh bad_mesh;
    bad_mesh.vertices.assign(3, Eigen::Vector3f::Zero());
    bad_mesh.triangles.emplace_back(0, 1, 3);
    EXPECT_THROW(io::WritePlyMesh(path, bad_mesh), DataError);
    EXPECT_THROW(io::WritePly(dir / "no_such_folder" / "x.ply", FullCloud(3)), IoError);

    EXPECT_EQ(io::ReadFileBytes(path), before);
    std::size_t files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
        (void)entry;
        ++files;
    }
    EXPECT_EQ(files, 1u);  // no temporary left behind
}

TEST(Ply, OrganizedCloudIsWrittenUnorganized) {
    test::TempDir dir;
    PointCloud c = test::RandomCloud(12);
    c.width = 4;
    c.height = 3;
    io::WritePointCloud(dir / "o.ply", c, io::Encoding::kBinary);
    const PointCloud r = io::ReadPointCloud(dir / "o.ply");
    ExpectSameVectors(c.points, r.points);
    EXPECT_EQ(r.width, 12u);
    EXPECT_EQ(r.height, 1u);
}

// ---------------------------------------------------------------------------------------------
// OBJ

io::ObjMesh ReadObjText(const test::TempDir& dir, const std::string& text,
                        const std::string& name = "m.obj") {
    WriteBytes(dir / name, text);
    return io::ReadObj(dir / name);
}

TEST(Obj, AllFaceFormsAndNegativeIndices) {
    test::TempDir dir;
    const io::ObjMesh o = ReadObjText(dir,
                                      "# a square and a triangle\n"
                                      "mtllib m.mtl\n"
                                      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                      "vt 0 0\nvt 1 0\nvt 1 1\n"
                                      "vn 0 0 1\n"
                                      "usemtl red\ns off\n"
                                      "f 1 2 3\n"
                                      "f 1/1 3/3 4/2\n"
                                      "f 1//1 2//1 3//1\r\n"
                                      "f 1/1/1 2/2/1 3/3/1 4/1/1\n"
                                      "v 2 0 0\n"
                                      "f -4 -1 -3\n"
                                      "l 1 2\n");
    const TriangleMesh& m = o.mesh;
    ASSERT_EQ(m.vertices.size(), 5u);
    EXPECT_EQ(m.vertices[4], Eigen::Vector3f(2, 0, 0));
    const std::vector<Triangle> expected = {{0, 1, 2}, {0, 2, 3}, {0, 1, 2},
                                            {0, 1, 2}, {0, 2, 3}, {1, 4, 2}};
    EXPECT_EQ(m.triangles, expected);
    EXPECT_FALSE(m.HasVertexNormals());  // not every corner names a normal
    EXPECT_FALSE(m.HasVertexColors());
    EXPECT_EQ(o.group_names, (std::vector<std::string>{""}));
    EXPECT_EQ(o.triangle_groups, std::vector<std::uint32_t>(6, 0));
}

TEST(Obj, GroupsColoursAndConsistentNormals) {
    test::TempDir dir;
    const io::ObjMesh o = ReadObjText(dir,
                                      "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\n"
                                      "v 0 1 0 0.5 0.5 0.5\nv 5 5 5 0 0 0\n"
                                      "vn 0 0 1\nvn 0 0 -1\nvn 0 0 1\n"
                                      "o leg_1\n# source part\n"
                                      "f 1//1 2//1 3//3\n"
                                      "g  top shelf \n"
                                      "f 1//1 3//3 4//1\n"
                                      "o leg_1\n"
                                      "f 4//1 3//1 1//1\n");
    EXPECT_EQ(o.group_names, (std::vector<std::string>{"leg_1", "top shelf"}));
    EXPECT_EQ(o.triangle_groups, (std::vector<std::uint32_t>{0, 1, 0}));
    const TriangleMesh& m = o.mesh;
    ASSERT_EQ(m.vertex_colors.size(), 5u);
    EXPECT_EQ(m.vertex_colors[0], (Color{255, 0, 0, 255}));
    EXPECT_EQ(m.vertex_colors[3], (Color{128, 128, 128, 255}));
    // vn 1 and vn 3 are equal, so vertex 3 has one normal; vertex 5 is used by no face.
    ASSERT_EQ(m.vertex_normals.size(), 5u);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(m.vertex_normals[i], Eigen::Vector3f(0, 0, 1));
    EXPECT_TRUE(std::isnan(m.vertex_normals[4].x()));
    EXPECT_NO_THROW(m.Validate());
}

TEST(Obj, ConflictingNormalsAndPartialColoursAreDropped) {
    test::TempDir dir;
    const io::ObjMesh o = ReadObjText(dir,
                                      "v 0 0 0 1 0 0\nv 1 0 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\n"
                                      "vn 0 0 1\nvn 0 0 -1\n"
                                      "f 1//1 2//1 3//1\nf 1//2 3//2 4//2\n");
    EXPECT_FALSE(o.mesh.HasVertexColors());
    EXPECT_FALSE(o.mesh.HasVertexNormals());
    EXPECT_EQ(o.mesh.triangles.size(), 2u);
}

TEST(Obj, EmptyFileGivesEmptyMesh) {
    test::TempDir dir;
    const io::ObjMesh o = ReadObjText(dir, "# nothing\n");
    EXPECT_TRUE(o.mesh.empty());
    EXPECT_TRUE(o.group_names.empty());
    EXPECT_TRUE(o.triangle_groups.empty());
}

TEST(Obj, ErrorsNameFileAndLine) {
    test::TempDir dir;
    auto expect_error = [&](const std::string& text, const std::string& part) {
        SCOPED_TRACE(text);
        try {
            (void)ReadObjText(dir, text, "bad.obj");
            ADD_FAILURE() << "no exception";
        } catch (const FormatError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("bad.obj"), std::string::npos) << what;
            EXPECT_NE(what.find(part), std::string::npos) << what;
        }
    };
    expect_error("v 0 0 0\nv 1 0 zero\n", "line 2: bad number 'zero'");
    expect_error("v 0 0\n", "line 1: v needs 3");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\nf 1 2 3\n",
                 "line 4: face refers to vertex 4 of 3");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "line 4: face needs at least 3");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", "line 4: relative vertex index -4");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4: index 0");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a 2 3\n", "line 4: bad face corner '1/a'");
    expect_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n",
                 "line 5: face refers to normal 2 of 1");
}

TEST(MeshIo, ReadTriangleMeshDispatchesOnExtension) {
    test::TempDir dir;
    WriteBytes(dir / "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_EQ(io::ReadTriangleMesh(dir / "t.obj").triangles.size(), 1u);
    TriangleMesh m;
    m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    io::WritePlyMesh(dir / "t.ply", m);
    EXPECT_EQ(io::ReadTriangleMesh(dir / "t.ply").triangles, m.triangles);
}

// ---------------------------------------------------------------------------------------------
// Shared data

TEST(SharedData, BenchmarkPlyCounts) {
    if (!test::HasSharedData()) GTEST_SKIP() << "no shared data";
    struct Expected {
        const char* file;
        std::size_t vertices;
        std::size_t faces;
        bool normals;
    };
    const Expected files[] = {{"bun_zipper.ply", 35947, 69451, false},
                              {"parasaurolophus_low_normals2.ply", 28291, 54839, true},
                              {"parasaurolophus_6700.ply", 6700, 9140, true},
                              {"Armadillo.ply", 38294, 0, true}};
    for (const auto& f : files) {
        SCOPED_TRACE(f.file);
        const auto path = test::SharedData(std::string("meshes/benchmark/") + f.file);
        const TriangleMesh m = io::ReadPlyMesh(path);
        EXPECT_EQ(m.vertices.size(), f.vertices);
        EXPECT_EQ(m.triangles.size(), f.faces);
        EXPECT_EQ(m.HasVertexNormals(), f.normals);
        EXPECT_NO_THROW(m.Validate());
    }
    const PointCloud bunny = io::ReadPly(test::SharedData("meshes/benchmark/bun_zipper.ply"));
    EXPECT_EQ(bunny.size(), 35947u);
    EXPECT_TRUE(bunny.HasIntensity());
    EXPECT_TRUE(bunny.HasConfidence());
    EXPECT_TRUE(bunny.extra_fields.empty());
    Eigen::Vector3f lo, hi;
    ASSERT_TRUE(ComputeBounds(bunny, lo, hi));
    const Eigen::Vector3f extent = hi - lo;
    EXPECT_NEAR(extent.x(), 0.156f, 0.001f);
    EXPECT_NEAR(extent.y(), 0.154f, 0.001f);
    EXPECT_NEAR(extent.z(), 0.121f, 0.001f);
}

TEST(SharedData, EveryTabletopMeshHasTriangles) {
    if (!test::HasSharedData()) GTEST_SKIP() << "no shared data";
    std::size_t obj = 0;
    std::size_t ply = 0;
    for (const auto& entry :
         std::filesystem::directory_iterator(test::SharedData("meshes/tabletop"))) {
        const std::string ext = io::LowerExtension(entry.path());
        if (ext != "obj" && ext != "ply") continue;
        SCOPED_TRACE(entry.path().filename().string());
        const TriangleMesh m = io::ReadTriangleMesh(entry.path());
        EXPECT_GT(m.triangles.size(), 0u);
        EXPECT_NO_THROW(m.Validate());
        if (ext == "obj") {
            ++obj;
            EXPECT_GE(m.vertices.size(), 346u);
            EXPECT_LE(m.vertices.size(), 440u);
        } else {
            ++ply;
            EXPECT_GE(m.vertices.size(), 60u);
            EXPECT_LE(m.vertices.size(), 10002u);
        }
    }
    EXPECT_EQ(obj, 129u);
    EXPECT_EQ(ply, 58u);
}

TEST(SharedData, FurniturePartGroupsMatchLabels) {
    if (!test::HasSharedData()) GTEST_SKIP() << "no shared data";
    std::ifstream csv(test::SharedData("meshes/furniture/labels.csv"));
    ASSERT_TRUE(csv);
    std::string line;
    std::getline(csv, line);  // header
    std::size_t files = 0;
    while (std::getline(csv, line)) {
        if (line.empty()) continue;
        // file,category,model_id,parts,...; parts = "19: drawer=4 handle=1 ..."
        std::vector<std::string> cols;
        std::stringstream ss(line);
        for (std::string col; cols.size() < 4 && std::getline(ss, col, ',');) cols.push_back(col);
        ASSERT_EQ(cols.size(), 4u) << line;
        SCOPED_TRACE(cols[0]);
        std::stringstream parts(cols[3]);
        std::string total;
        parts >> total;
        std::map<std::string, std::size_t> expected;
        for (std::string kv; parts >> kv;) {
            const auto eq = kv.find('=');
            expected[kv.substr(0, eq)] = std::stoul(kv.substr(eq + 1));
        }
        const io::ObjMesh o = io::ReadObj(test::SharedData("meshes/furniture/" + cols[0]));
        EXPECT_EQ(o.group_names.size(), std::stoul(total));
        std::map<std::string, std::size_t> found;
        for (const auto& g : o.group_names) {
            const auto us = g.rfind('_');
            ASSERT_NE(us, std::string::npos) << g;
            ++found[g.substr(0, us)];
        }
        EXPECT_EQ(found, expected);
        ASSERT_EQ(o.triangle_groups.size(), o.mesh.triangles.size());
        EXPECT_NO_THROW(o.mesh.Validate());
        ++files;
    }
    EXPECT_EQ(files, 11u);

    const io::ObjMesh table = io::ReadObj(test::SharedData("meshes/furniture/table__22339.obj"));
    EXPECT_EQ(table.group_names.size(), 19u);
    EXPECT_EQ(table.group_names.front(), "drawer_1");
    EXPECT_EQ(table.mesh.vertices.size(), 1681u);
    EXPECT_EQ(table.mesh.triangles.size(), 6634u);
}

}  // namespace
}  // namespace multicue
