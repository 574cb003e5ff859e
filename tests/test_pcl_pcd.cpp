// PCD interoperability with PCL 1.13: files multicue writes load in PCL, and files PCL writes
// (ascii, binary, binary_compressed) read in multicue, with the same values.

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "multicue/core/exceptions.hpp"
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

bool SameFloat(float a, float b) {
    return (std::isnan(a) && std::isnan(b)) ||
           std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

#define EXPECT_SAME_FLOAT(a, b) EXPECT_PRED2(SameFloat, a, b)

const char* EncodingName(PcdEncoding e) {
    return e == PcdEncoding::kAscii ? "Ascii" : e == PcdEncoding::kBinary ? "Binary" : "Compressed";
}

/// A 4x3 organized cloud with NaN points, normals, curvature, colours and a sensor pose.
PointCloud MakeOrganized(bool translucent) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-2.0f, 2.0f);
    PointCloud c;
    c.points.resize(12);
    c.normals.resize(12);
    c.curvature.resize(12);
    c.colors.resize(12);
    for (std::size_t i = 0; i < 12; ++i) {
        c.points[i] = {u(rng), u(rng), u(rng) / 3.0f};
        c.normals[i] = Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized();
        c.curvature[i] = u(rng) * 1e-3f;
        c.colors[i] = {static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()),
                       static_cast<std::uint8_t>(rng()),
                       static_cast<std::uint8_t>(translucent ? rng() : 255)};
    }
    c.points[2] = Eigen::Vector3f::Constant(kNaN);
    c.normals[2] = Eigen::Vector3f::Constant(kNaN);
    c.curvature[2] = kNaN;
    c.points[9] = Eigen::Vector3f::Constant(kNaN);
    c.width = 4;
    c.height = 3;
    c.sensor_origin = {1.0f, 2.5f, -3.0f};
    c.sensor_orientation = Eigen::Quaternionf(0.5f, 0.5f, -0.5f, 0.5f);
    return c;
}

template <typename PointT>
void ExpectSamePose(const pcl::PointCloud<PointT>& p, const PointCloud& c) {
    EXPECT_EQ(Eigen::Vector3f(p.sensor_origin_.x(), p.sensor_origin_.y(), p.sensor_origin_.z()),
              c.sensor_origin);
    EXPECT_EQ(p.sensor_orientation_.coeffs(), c.sensor_orientation.coeffs());
}

// ------------------------------------------------------------------ multicue writes, PCL reads

class PcdWrittenByMulticue : public ::testing::TestWithParam<PcdEncoding> {
  protected:
    fs::path Write(const PointCloud& c) {
        const fs::path p = dir_ / "multicue.pcd";
        WritePcd(p, c, {.encoding = GetParam()});
        return p;
    }
    test::TempDir dir_;
};

TEST_P(PcdWrittenByMulticue, LoadsAsPointXYZRGBNormal) {
    const PointCloud c = MakeOrganized(false);
    pcl::PointCloud<pcl::PointXYZRGBNormal> p;
    ASSERT_EQ(pcl::io::loadPCDFile(Write(c).string(), p), 0);
    ASSERT_EQ(p.size(), c.size());
    EXPECT_EQ(p.width, 4u);
    EXPECT_EQ(p.height, 3u);
    EXPECT_FALSE(p.is_dense);
    ExpectSamePose(p, c);
    for (std::size_t i = 0; i < c.size(); ++i) {
        SCOPED_TRACE(i);
        const auto& q = p[i];
        EXPECT_SAME_FLOAT(q.x, c.points[i].x());
        EXPECT_SAME_FLOAT(q.y, c.points[i].y());
        EXPECT_SAME_FLOAT(q.z, c.points[i].z());
        EXPECT_SAME_FLOAT(q.normal_x, c.normals[i].x());
        EXPECT_SAME_FLOAT(q.normal_y, c.normals[i].y());
        EXPECT_SAME_FLOAT(q.normal_z, c.normals[i].z());
        EXPECT_SAME_FLOAT(q.curvature, c.curvature[i]);
        EXPECT_EQ((Color{q.r, q.g, q.b, q.a}), c.colors[i]);
    }
}

TEST_P(PcdWrittenByMulticue, LoadsAsPointXYZRGBLAndPointXYZRGBAWithAlpha) {
    PointCloud c = MakeOrganized(true);
    c.normals.clear();
    c.curvature.clear();
    c.labels.resize(c.size());
    for (std::size_t i = 0; i < c.size(); ++i)
        c.labels[i] = static_cast<std::uint32_t>(i * 1000003u);
    pcl::PointCloud<pcl::PointXYZRGBL> p;
    ASSERT_EQ(pcl::io::loadPCDFile(Write(c).string(), p), 0);
    ASSERT_EQ(p.size(), c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        EXPECT_SAME_FLOAT(p[i].x, c.points[i].x());
        EXPECT_EQ((Color{p[i].r, p[i].g, p[i].b, p[i].a}), c.colors[i]) << i;
        EXPECT_EQ(p[i].label, c.labels[i]);
    }
    pcl::PointCloud<pcl::PointXYZRGBA> q;
    ASSERT_EQ(pcl::io::loadPCDFile(Write(c).string(), q), 0);
    ASSERT_EQ(q.size(), c.size());
    EXPECT_EQ(q.width, 4u);
    EXPECT_EQ(q.height, 3u);
    for (std::size_t i = 0; i < c.size(); ++i) {
        EXPECT_SAME_FLOAT(q[i].z, c.points[i].z());
        EXPECT_EQ((Color{q[i].r, q[i].g, q[i].b, q[i].a}), c.colors[i]) << i;
    }
}

TEST_P(PcdWrittenByMulticue, LoadsIntensityAndExtraFieldsAsPCLPointCloud2) {
    PointCloud c = test::RandomCloud(50, 4);
    std::mt19937 rng(2);
    c.intensity.resize(c.size());
    for (auto& v : c.intensity) v = std::uniform_real_distribution<float>(0.0f, 1000.0f)(rng);
    const struct {
        const char* name;
        char type;
        std::uint8_t size;
        std::uint32_t count;
        std::uint8_t pcl_type;
    } extras[] = {{"ring", 'U', 1, 1, pcl::PCLPointField::UINT8},
                  {"moment", 'I', 2, 3, pcl::PCLPointField::INT16},
                  {"timestamp", 'F', 8, 1, pcl::PCLPointField::FLOAT64},
                  {"fpfh", 'F', 4, 33, pcl::PCLPointField::FLOAT32},
                  {"object", 'U', 8, 1, pcl::PCLPointField::UINT64}};
    for (const auto& e : extras) {
        ExtraField f{e.name, e.type, e.size, e.count, {}};
        f.data.resize(c.size() * f.BytesPerPoint());
        for (std::size_t k = 0; k < c.size() * e.count; ++k) {
            // Small integers in every type: valid in ascii for all of them.
            const auto v = static_cast<std::int8_t>(rng() % 100);
            std::uint8_t* dst = f.data.data() + k * e.size;
            if (e.type == 'F' && e.size == 4) {
                const float x = v / 8.0f;
                std::memcpy(dst, &x, 4);
            } else if (e.type == 'F') {
                const double x = v / 3.0;
                std::memcpy(dst, &x, 8);
            } else {
                const std::int64_t x = v;
                std::memcpy(dst, &x, e.size);
            }
        }
        c.extra_fields.push_back(std::move(f));
    }
    pcl::PCLPointCloud2 p;
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    ASSERT_EQ(pcl::io::loadPCDFile(Write(c).string(), p, origin, orientation), 0);
    ASSERT_EQ(p.width * p.height, c.size());
    EXPECT_EQ(p.height, 1u);
    ASSERT_EQ(p.fields.size(), 4u + std::size(extras));
    EXPECT_EQ(p.fields[3].name, "intensity");
    for (std::size_t i = 0; i < c.size(); ++i) {
        float v;
        std::memcpy(&v, &p.data[i * p.point_step + p.fields[3].offset], 4);
        EXPECT_EQ(v, c.intensity[i]);
    }
    for (std::size_t j = 0; j < std::size(extras); ++j) {
        const pcl::PCLPointField& f = p.fields[4 + j];
        const ExtraField& e = c.extra_fields[j];
        SCOPED_TRACE(e.name);
        EXPECT_EQ(f.name, e.name);
        EXPECT_EQ(f.datatype, extras[j].pcl_type);
        EXPECT_EQ(f.count, e.count);
        for (std::size_t i = 0; i < c.size(); ++i) {
            ASSERT_EQ(std::memcmp(&p.data[i * p.point_step + f.offset],
                                  e.data.data() + i * e.BytesPerPoint(), e.BytesPerPoint()),
                      0)
                << "point " << i;
        }
    }
}

TEST_P(PcdWrittenByMulticue, IncompressibleDataLoads) {
    PointCloud c = test::RandomCloud(200, 8);
    std::mt19937 rng(3);
    ExtraField noise{"noise", 'U', 1, 32, std::vector<std::uint8_t>(c.size() * 32)};
    for (auto& b : noise.data) b = static_cast<std::uint8_t>(rng());
    c.extra_fields.push_back(noise);
    pcl::PCLPointCloud2 p;
    ASSERT_EQ(pcl::io::loadPCDFile(Write(c).string(), p), 0);
    ASSERT_EQ(p.width, c.size());
    ASSERT_EQ(p.fields.size(), 4u);
    for (std::size_t i = 0; i < c.size(); ++i) {
        ASSERT_EQ(std::memcmp(&p.data[i * p.point_step + p.fields[3].offset],
                              noise.data.data() + i * 32, 32),
                  0);
    }
}

TEST_P(PcdWrittenByMulticue, EmptyCloudLoads) {
    pcl::PointCloud<pcl::PointXYZ> p;
    p.push_back(pcl::PointXYZ(1, 2, 3));
    const auto verbosity = pcl::console::getVerbosityLevel();
    pcl::console::setVerbosityLevel(pcl::console::L_ERROR);  // PCL warns about empty clouds
    const int rc = pcl::io::loadPCDFile(Write(PointCloud{}).string(), p);
    pcl::console::setVerbosityLevel(verbosity);
    ASSERT_EQ(rc, 0);
    EXPECT_TRUE(p.empty());
}

INSTANTIATE_TEST_SUITE_P(Encodings, PcdWrittenByMulticue,
                         ::testing::Values(PcdEncoding::kAscii, PcdEncoding::kBinary,
                                           PcdEncoding::kBinaryCompressed),
                         [](const auto& param_info) { return EncodingName(param_info.param); });

// ------------------------------------------------------------------ PCL writes, multicue reads

class PcdWrittenByPcl : public ::testing::TestWithParam<PcdEncoding> {
  protected:
    template <typename PointT>
    fs::path Save(const pcl::PointCloud<PointT>& p) {
        const fs::path path = dir_ / "pcl.pcd";
        const std::string name = path.string();
        int rc = -1;
        switch (GetParam()) {
            case PcdEncoding::kAscii:
                rc = pcl::io::savePCDFileASCII(name, p);
                break;
            case PcdEncoding::kBinary:
                rc = pcl::io::savePCDFileBinary(name, p);
                break;
            case PcdEncoding::kBinaryCompressed:
                rc = pcl::io::savePCDFileBinaryCompressed(name, p);
                break;
        }
        EXPECT_EQ(rc, 0);
        return path;
    }
    fs::path Save(const pcl::PCLPointCloud2& p) {
        const fs::path path = dir_ / "pcl2.pcd";
        const std::string name = path.string();
        const Eigen::Vector4f origin(0.25f, 0.5f, 0.75f, 0.0f);
        const Eigen::Quaternionf orientation(0.0f, 0.0f, 1.0f, 0.0f);
        pcl::PCDWriter w;
        int rc = -1;
        switch (GetParam()) {
            case PcdEncoding::kAscii:
                rc = w.writeASCII(name, p, origin, orientation, 17);
                break;
            case PcdEncoding::kBinary:
                rc = w.writeBinary(name, p, origin, orientation);
                break;
            case PcdEncoding::kBinaryCompressed:
                rc = w.writeBinaryCompressed(name, p, origin, orientation);
                break;
        }
        EXPECT_EQ(rc, 0);
        return path;
    }
    test::TempDir dir_;
};

TEST_P(PcdWrittenByPcl, OrganizedPointXYZRGBNormalWithNaNs) {
    const PointCloud ref = MakeOrganized(false);
    pcl::PointCloud<pcl::PointXYZRGBNormal> p(4, 3);
    for (std::size_t i = 0; i < ref.size(); ++i) {
        auto& q = p[i];
        q.x = ref.points[i].x();
        q.y = ref.points[i].y();
        q.z = ref.points[i].z();
        q.normal_x = ref.normals[i].x();
        q.normal_y = ref.normals[i].y();
        q.normal_z = ref.normals[i].z();
        q.curvature = ref.curvature[i];
        q.r = ref.colors[i].r;
        q.g = ref.colors[i].g;
        q.b = ref.colors[i].b;
        q.a = ref.colors[i].a;
    }
    p.is_dense = false;
    p.sensor_origin_ << ref.sensor_origin, 0.0f;
    p.sensor_orientation_ = ref.sensor_orientation;
    const PointCloud c = ReadPcd(Save(p));
    ASSERT_EQ(c.size(), ref.size());
    EXPECT_TRUE(c.IsOrganized());
    EXPECT_EQ(c.width, 4u);
    EXPECT_EQ(c.height, 3u);
    EXPECT_EQ(c.sensor_origin, ref.sensor_origin);
    EXPECT_EQ(c.sensor_orientation.coeffs(), ref.sensor_orientation.coeffs());
    ASSERT_TRUE(c.HasNormals());
    ASSERT_TRUE(c.HasCurvature());
    ASSERT_TRUE(c.HasColors());
    EXPECT_TRUE(c.extra_fields.empty());
    for (std::size_t i = 0; i < ref.size(); ++i) {
        SCOPED_TRACE(i);
        for (int k = 0; k < 3; ++k) {
            EXPECT_SAME_FLOAT(c.points[i][k], ref.points[i][k]);
            EXPECT_SAME_FLOAT(c.normals[i][k], ref.normals[i][k]);
        }
        EXPECT_SAME_FLOAT(c.curvature[i], ref.curvature[i]);
        EXPECT_EQ(c.colors[i], ref.colors[i]);
    }
}

TEST_P(PcdWrittenByPcl, PointXYZRGBAKeepsAlpha) {
    pcl::PointCloud<pcl::PointXYZRGBA> p;
    std::mt19937 rng(6);
    for (int i = 0; i < 40; ++i) {
        pcl::PointXYZRGBA q;
        q.x = static_cast<float>(i) / 7.0f;
        q.y = -q.x;
        q.z = 1.0f;
        q.rgba = static_cast<std::uint32_t>(rng());
        p.push_back(q);
    }
    const PointCloud c = ReadPcd(Save(p));
    ASSERT_EQ(c.size(), p.size());
    EXPECT_FALSE(c.IsOrganized());
    for (std::size_t i = 0; i < p.size(); ++i) {
        EXPECT_SAME_FLOAT(c.points[i].x(), p[i].x);
        EXPECT_EQ(c.colors[i], (Color{p[i].r, p[i].g, p[i].b, p[i].a}));
    }
}

TEST_P(PcdWrittenByPcl, LabelsAndIntensity) {
    pcl::PointCloud<pcl::PointXYZL> labelled;
    pcl::PointCloud<pcl::PointXYZI> intense;
    for (int i = 0; i < 30; ++i) {
        pcl::PointXYZL l;
        l.x = l.y = l.z = static_cast<float>(i) * 0.1f;
        l.label = static_cast<std::uint32_t>(i * 77777);
        labelled.push_back(l);
        pcl::PointXYZI in;
        in.x = in.y = in.z = static_cast<float>(i) * 0.2f;
        in.intensity = static_cast<float>(i) / 3.0f;
        intense.push_back(in);
    }
    const PointCloud c = ReadPcd(Save(labelled));
    ASSERT_EQ(c.labels.size(), labelled.size());
    for (std::size_t i = 0; i < labelled.size(); ++i) EXPECT_EQ(c.labels[i], labelled[i].label);
    const PointCloud d = ReadPcd(Save(intense));
    ASSERT_EQ(d.intensity.size(), intense.size());
    for (std::size_t i = 0; i < intense.size(); ++i) {
        EXPECT_SAME_FLOAT(d.intensity[i], intense[i].intensity);
        EXPECT_SAME_FLOAT(d.points[i].z(), intense[i].z);
    }
}

TEST_P(PcdWrittenByPcl, PCLPointCloud2WithCustomFields) {
    // x y z float, "object" int16 x3, "timestamp" float64: laid out by hand as PCL stores them.
    pcl::PCLPointCloud2 p;
    const auto field = [](const char* name, std::uint32_t offset, std::uint8_t type,
                          std::uint32_t count) {
        pcl::PCLPointField f;
        f.name = name;
        f.offset = offset;
        f.datatype = type;
        f.count = count;
        return f;
    };
    p.fields = {field("x", 0, pcl::PCLPointField::FLOAT32, 1),
                field("y", 4, pcl::PCLPointField::FLOAT32, 1),
                field("z", 8, pcl::PCLPointField::FLOAT32, 1),
                field("object", 12, pcl::PCLPointField::INT16, 3),
                field("timestamp", 18, pcl::PCLPointField::FLOAT64, 1)};
    p.point_step = 26;
    p.width = 5;
    p.height = 2;
    p.row_step = p.point_step * p.width;
    p.is_dense = false;
    p.data.resize(std::size_t{p.row_step} * p.height);
    for (std::uint32_t i = 0; i < 10; ++i) {
        std::uint8_t* rec = &p.data[i * p.point_step];
        const float xyz[3] = {i == 4 ? kNaN : 0.1f * i, 0.5f, -1.0f * i};
        const std::int16_t obj[3] = {static_cast<std::int16_t>(-i), 7, 300};
        const double t = 1.7e9 + i / 3.0;
        std::memcpy(rec, xyz, 12);
        std::memcpy(rec + 12, obj, 6);
        std::memcpy(rec + 18, &t, 8);
    }
    const PointCloud c = ReadPcd(Save(p));
    ASSERT_EQ(c.size(), 10u);
    EXPECT_EQ(c.width, 5u);
    EXPECT_EQ(c.height, 2u);
    EXPECT_EQ(c.sensor_origin, Eigen::Vector3f(0.25f, 0.5f, 0.75f));
    EXPECT_EQ(c.sensor_orientation.coeffs(), Eigen::Quaternionf(0, 0, 1, 0).coeffs());
    ASSERT_EQ(c.extra_fields.size(), 2u);
    const ExtraField& obj = c.extra_fields[0];
    const ExtraField& ts = c.extra_fields[1];
    EXPECT_EQ(obj.name, "object");
    EXPECT_EQ(obj.type, 'I');
    EXPECT_EQ(obj.size, 2u);
    EXPECT_EQ(obj.count, 3u);
    EXPECT_EQ(ts.name, "timestamp");
    EXPECT_EQ(ts.type, 'F');
    EXPECT_EQ(ts.size, 8u);
    for (std::uint32_t i = 0; i < 10; ++i) {
        const std::uint8_t* rec = &p.data[i * p.point_step];
        float x;
        std::memcpy(&x, rec, 4);
        EXPECT_SAME_FLOAT(c.points[i].x(), x);
        EXPECT_EQ(std::memcmp(obj.data.data() + i * 6, rec + 12, 6), 0) << i;
        double t, u;
        std::memcpy(&t, rec + 18, 8);
        std::memcpy(&u, ts.data.data() + i * 8, 8);
        EXPECT_EQ(u, t) << i;
    }
}

TEST_P(PcdWrittenByPcl, EmptyCloud) {
    const auto verbosity = pcl::console::getVerbosityLevel();
    pcl::console::setVerbosityLevel(pcl::console::L_ERROR);  // PCL warns about empty clouds
    const PointCloud c = ReadPcd(Save(pcl::PointCloud<pcl::PointXYZ>()));
    pcl::console::setVerbosityLevel(verbosity);
    EXPECT_TRUE(c.empty());
    EXPECT_EQ(c.width, 0u);
    EXPECT_EQ(c.height, 1u);
}

INSTANTIATE_TEST_SUITE_P(Encodings, PcdWrittenByPcl,
                         ::testing::Values(PcdEncoding::kAscii, PcdEncoding::kBinary,
                                           PcdEncoding::kBinaryCompressed),
                         [](const auto& param_info) { return EncodingName(param_info.param); });

// ----------------------------------------------------------------------------- shared scans

/// Counts points whose coordinates differ from PCL's (NaN-aware, bit for bit).
template <typename PointT>
std::size_t DifferingPoints(const pcl::PointCloud<PointT>& p, const PointCloud& c) {
    std::size_t differing = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        differing += !SameFloat(p[i].x, c.points[i].x()) || !SameFloat(p[i].y, c.points[i].y()) ||
                     !SameFloat(p[i].z, c.points[i].z());
    }
    return differing;
}

TEST(PclPcdSharedData, SameValuesAsPclOnRealScans) {
    if (!test::HasSharedData()) GTEST_SKIP() << "shared data not available";
    const fs::path scans = test::SharedData("scans");
    {
        // rgb: alpha 0 reads as opaque in multicue, PCL keeps the stored byte.
        const PointCloud c = ReadPcd(scans / "table_scene_mug_stereo_textured.pcd");
        pcl::PointCloud<pcl::PointXYZRGB> p;
        ASSERT_EQ(pcl::io::loadPCDFile((scans / "table_scene_mug_stereo_textured.pcd").string(), p),
                  0);
        ASSERT_EQ(p.size(), c.size());
        EXPECT_EQ(p.width, c.width);
        EXPECT_EQ(p.height, c.height);
        ExpectSamePose(p, c);
        EXPECT_EQ(DifferingPoints(p, c), 0u);
        std::size_t colors = 0, opaque = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            const std::uint8_t alpha = p[i].a == 0 ? 255 : p[i].a;
            colors += Color{p[i].r, p[i].g, p[i].b, alpha} != c.colors[i];
            opaque += p[i].a == 0;
        }
        EXPECT_EQ(colors, 0u);
        EXPECT_GT(opaque, 0u);
    }
    {
        const fs::path path = scans / "mosd-learn/learn7.pcd";
        const PointCloud c = ReadPcd(path);
        pcl::PointCloud<pcl::PointXYZRGBL> p;
        ASSERT_EQ(pcl::io::loadPCDFile(path.string(), p), 0);
        ASSERT_EQ(p.size(), c.size());
        EXPECT_EQ(DifferingPoints(p, c), 0u);
        std::size_t differing = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            differing += Color{p[i].r, p[i].g, p[i].b, p[i].a} != c.colors[i];
            differing += p[i].label != c.labels[i];
        }
        EXPECT_EQ(differing, 0u);
    }
    {
        const fs::path path = scans / "bun0.pcd";
        const PointCloud c = ReadPcd(path);
        pcl::PointCloud<pcl::PointNormal> p;
        ASSERT_EQ(pcl::io::loadPCDFile(path.string(), p), 0);
        ASSERT_EQ(p.size(), c.size());
        EXPECT_EQ(DifferingPoints(p, c), 0u);
        std::size_t differing = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            for (int k = 0; k < 3; ++k) differing += !SameFloat(p[i].data_n[k], c.normals[i][k]);
            differing += !SameFloat(p[i].curvature, c.curvature[i]);
        }
        EXPECT_EQ(differing, 0u);
    }
}

}  // namespace
}  // namespace multicue
