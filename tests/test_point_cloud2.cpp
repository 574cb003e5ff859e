// sensor_msgs/PointCloud2 <-> PointCloud: round trips of every field, hand-built layouts with
// padding and odd types, byte-swapped data, and layouts that do not fit their data.

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/cdr.hpp"
#include "multicue/io/depth_image.hpp"
#include "multicue/io/point_cloud2.hpp"
#include "multicue/io/ros_messages.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

using io::PointCloud2Message;
using io::PointField;
using io::PointFieldType;

constexpr std::uint8_t T(PointFieldType t) { return static_cast<std::uint8_t>(t); }

/// A cloud with every kind of field, some points NaN.
PointCloud FullCloud(std::uint32_t width, std::uint32_t height) {
    PointCloud c = test::RandomCloud(std::size_t{width} * height, 7);
    const std::size_t n = c.size();
    c.points[1] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
    c.normals.resize(n);
    c.curvature.resize(n);
    c.colors.resize(n);
    c.intensity.resize(n);
    c.confidence.resize(n);
    c.labels.resize(n);
    ExtraField ring{"ring", 'U', 2, 1, {}};
    ExtraField hist{"hist", 'F', 8, 3, {}};
    ring.data.resize(n * 2);
    hist.data.resize(n * 24);
    for (std::size_t i = 0; i < n; ++i) {
        c.normals[i] = Eigen::Vector3f(float(i), 1, 2).normalized();
        c.curvature[i] = 0.01f * float(i);
        c.colors[i] = Color{std::uint8_t(i), std::uint8_t(2 * i), std::uint8_t(3 * i),
                            std::uint8_t(i % 2 ? 255 : 128)};
        c.intensity[i] = float(i) * 0.5f;
        c.confidence[i] = 1.0f / float(i + 1);
        c.labels[i] = std::uint32_t(i * 1000);
        const std::uint16_t r = std::uint16_t(i % 16);
        std::memcpy(ring.data.data() + 2 * i, &r, 2);
        for (int k = 0; k < 3; ++k) {
            const double h = double(i) + 0.25 * k;
            std::memcpy(hist.data.data() + 24 * i + 8 * k, &h, 8);
        }
    }
    c.extra_fields = {ring, hist};
    c.width = width;
    c.height = height;
    if (height == 1) c.SetUnorganized();
    return c;
}

void ExpectSameVec(const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            if (std::isnan(a[i][k])) {
                EXPECT_TRUE(std::isnan(b[i][k])) << i;
            } else {
                EXPECT_EQ(a[i][k], b[i][k]) << i;
            }
        }
    }
}

void ExpectSameCloud(const PointCloud& a, const PointCloud& b, bool alpha = true) {
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    ExpectSameVec(a.points, b.points);
    ExpectSameVec(a.normals, b.normals);
    EXPECT_EQ(a.curvature, b.curvature);
    ASSERT_EQ(a.colors.size(), b.colors.size());
    for (std::size_t i = 0; i < a.colors.size(); ++i) {
        EXPECT_EQ(a.colors[i].r, b.colors[i].r);
        EXPECT_EQ(a.colors[i].g, b.colors[i].g);
        EXPECT_EQ(a.colors[i].b, b.colors[i].b);
        if (alpha) {
            EXPECT_EQ(a.colors[i].a, b.colors[i].a);
        }
    }
    EXPECT_EQ(a.intensity, b.intensity);
    EXPECT_EQ(a.confidence, b.confidence);
    EXPECT_EQ(a.labels, b.labels);
    ASSERT_EQ(a.extra_fields.size(), b.extra_fields.size());
    for (std::size_t k = 0; k < a.extra_fields.size(); ++k) {
        EXPECT_EQ(a.extra_fields[k].name, b.extra_fields[k].name);
        EXPECT_EQ(a.extra_fields[k].type, b.extra_fields[k].type);
        EXPECT_EQ(a.extra_fields[k].size, b.extra_fields[k].size);
        EXPECT_EQ(a.extra_fields[k].count, b.extra_fields[k].count);
        EXPECT_EQ(a.extra_fields[k].data, b.extra_fields[k].data);
    }
}

TEST(PointCloud2, RoundTripsEveryFieldUnorganizedAndOrganized) {
    for (const std::uint32_t height : {1u, 3u}) {
        for (const bool big : {false, true}) {
            for (const bool rgba : {false, true}) {
                const PointCloud cloud = FullCloud(4, height);
                const auto msg = io::ToPointCloud2(
                    cloud, {.big_endian = big, .point_alignment = 16, .rgba = rgba});
                EXPECT_EQ(msg.point_step % 16, 0u);
                EXPECT_EQ(msg.height, height);
                EXPECT_EQ(msg.is_bigendian, big);
                EXPECT_FALSE(msg.is_dense);  // one NaN point
                ASSERT_NE(msg.FindField(rgba ? "rgba" : "rgb"), nullptr);
                const PointCloud back = io::FromPointCloud2(msg);
                EXPECT_EQ(back.IsOrganized(), height > 1);
                // "rgb" reads alpha 0 as opaque but keeps other alphas: 128 and 255 survive.
                ExpectSameCloud(cloud, back);
            }
        }
    }
}

TEST(PointCloud2, BigEndianDataIsTheByteSwapOfLittleEndian) {
    const PointCloud cloud = FullCloud(5, 1);
    const auto le = io::ToPointCloud2(cloud);
    const auto be = io::ToPointCloud2(cloud, {.big_endian = true});
    ASSERT_EQ(le.fields, be.fields);
    ASSERT_EQ(le.data.size(), be.data.size());
    // x of point 0: four bytes reversed.
    for (int b = 0; b < 4; ++b) EXPECT_EQ(le.data[b], be.data[3 - b]);
    EXPECT_NE(le.data, be.data);
}

/// A little hand-built message: fields out of order, x as float64, y int16 (millimetres would
/// need scaling; here plain integers), z float32, a uint32 "rgb", 3 bytes of padding inside each
/// point and 5 bytes at the end of each row.
PointCloud2Message HandBuilt(bool big_endian) {
    PointCloud2Message m;
    m.width = 2;
    m.height = 2;
    m.is_bigendian = big_endian;
    m.fields = {{"rgb", 0, T(PointFieldType::kUInt32), 1},
                {"z", 4, T(PointFieldType::kFloat32), 1},
                {"x", 8, T(PointFieldType::kFloat64), 1},
                {"y", 16, T(PointFieldType::kInt16), 1},
                {"flag", 18, T(PointFieldType::kUInt8), 1}};
    m.point_step = 22;  // 19..21 padding
    m.row_step = 2 * 22 + 5;
    m.data.assign(m.row_step * 2, 0xEE);
    const auto put = [&](std::size_t at, const void* v, std::size_t n) {
        const auto* b = static_cast<const std::uint8_t*>(v);
        for (std::size_t k = 0; k < n; ++k) m.data[at + k] = big_endian ? b[n - 1 - k] : b[k];
    };
    for (std::uint32_t i = 0; i < 4; ++i) {
        const std::size_t base = (i / 2) * m.row_step + (i % 2) * m.point_step;
        const std::uint32_t rgb = 0x00102030u + i;  // alpha 0: opaque
        const float z = 1.5f + float(i);
        const double x = -0.25 * i;
        const std::int16_t y = static_cast<std::int16_t>(-7 * int(i));
        const std::uint8_t flag = std::uint8_t(i + 1);
        put(base + 0, &rgb, 4);
        put(base + 4, &z, 4);
        put(base + 8, &x, 8);
        put(base + 16, &y, 2);
        put(base + 18, &flag, 1);
    }
    return m;
}

TEST(PointCloud2, ReadsAHandBuiltLayoutWithPaddingInBothByteOrders) {
    for (const bool big : {false, true}) {
        const PointCloud c = io::FromPointCloud2(HandBuilt(big));
        ASSERT_EQ(c.size(), 4u);
        EXPECT_TRUE(c.IsOrganized());
        for (std::uint32_t i = 0; i < 4; ++i) {
            EXPECT_FLOAT_EQ(c.points[i].x(), float(-0.25 * i));
            EXPECT_FLOAT_EQ(c.points[i].y(), float(-7 * int(i)));
            EXPECT_FLOAT_EQ(c.points[i].z(), 1.5f + float(i));
            EXPECT_EQ(c.colors[i].r, 0x10);
            EXPECT_EQ(c.colors[i].g, 0x20);
            EXPECT_EQ(c.colors[i].b, 0x30 + i);
            EXPECT_EQ(c.colors[i].a, 255);
        }
        const ExtraField* flag = c.FindExtraField("flag");
        ASSERT_NE(flag, nullptr);
        EXPECT_EQ(flag->type, 'U');
        EXPECT_EQ(flag->data, (std::vector<std::uint8_t>{1, 2, 3, 4}));
    }
}

TEST(PointCloud2, SeparateColourChannels) {
    for (const auto type : {PointFieldType::kUInt8, PointFieldType::kFloat32}) {
        PointCloud2Message m;
        m.width = 1;
        const std::size_t cs = io::PointFieldTypeSize(T(type));
        m.fields = {{"x", 0, T(PointFieldType::kFloat32), 1},
                    {"y", 4, T(PointFieldType::kFloat32), 1},
                    {"z", 8, T(PointFieldType::kFloat32), 1},
                    {"r", 12, T(type), 1},
                    {"g", std::uint32_t(12 + cs), T(type), 1},
                    {"b", std::uint32_t(12 + 2 * cs), T(type), 1}};
        m.point_step = m.row_step = std::uint32_t(12 + 3 * cs);
        m.data.assign(m.point_step, 0);
        if (type == PointFieldType::kUInt8) {
            m.data[12] = 200, m.data[13] = 100, m.data[14] = 50;
        } else {
            const float v[3] = {200 / 255.0f, 100 / 255.0f, 50 / 255.0f};
            std::memcpy(m.data.data() + 12, v, 12);
        }
        const PointCloud c = io::FromPointCloud2(m);
        ASSERT_EQ(c.colors.size(), 1u);
        EXPECT_EQ(c.colors[0].r, 200);
        EXPECT_EQ(c.colors[0].g, 100);
        EXPECT_EQ(c.colors[0].b, 50);
        EXPECT_TRUE(c.extra_fields.empty());
    }
}

// A label field stored as float64 is read as integers; a value no uint32 holds is a format error
// (converting it would be undefined behaviour).
TEST(PointCloud2, FloatingPointLabelsMustFitTheLabelType) {
    PointCloud2Message m;
    m.width = 2;
    m.fields = {{"x", 0, T(PointFieldType::kFloat32), 1},
                {"y", 4, T(PointFieldType::kFloat32), 1},
                {"z", 8, T(PointFieldType::kFloat32), 1},
                {"label", 12, T(PointFieldType::kFloat64), 1}};
    m.point_step = 20;
    m.row_step = 40;
    m.data.assign(40, 0);
    const double labels[2] = {7.0, 3.0};
    std::memcpy(m.data.data() + 12, &labels[0], 8);
    std::memcpy(m.data.data() + 32, &labels[1], 8);
    EXPECT_EQ(io::FromPointCloud2(m).labels, (std::vector<std::uint32_t>{7, 3}));
    for (const double bad : {3.6e227, -2.0, std::nan("")}) {
        std::memcpy(m.data.data() + 32, &bad, 8);
        try {
            io::FromPointCloud2(m, "msg");
            ADD_FAILURE() << bad << " was read as a label";
        } catch (const FormatError& e) {
            EXPECT_NE(std::string(e.what()).find("field 'label' of point 1"), std::string::npos)
                << e.what();
        }
    }
}

TEST(PointCloud2, EmptyMessageGivesAnEmptyCloud) {
    PointCloud2Message m = io::ToPointCloud2(PointCloud{});
    EXPECT_EQ(m.width, 0u);
    const PointCloud c = io::FromPointCloud2(m);
    EXPECT_TRUE(c.empty());
}

TEST(PointCloud2, LayoutsThatDoNotFitTheirDataAreFormatErrors) {
    const auto expect_error = [](const PointCloud2Message& m, const std::string& part) {
        try {
            io::FromPointCloud2(m, "camera msg 3");
            ADD_FAILURE() << "no error, expected '" << part << "'";
        } catch (const FormatError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("camera msg 3"), std::string::npos) << what;
            EXPECT_NE(what.find(part), std::string::npos) << what;
        }
    };
    const PointCloud2Message good = HandBuilt(false);
    auto m = good;
    m.data.resize(m.data.size() - 10);
    expect_error(m, "truncated");
    m = good;
    m.fields.erase(m.fields.begin() + 2);  // no x
    expect_error(m, "no x/y/z fields (fields: rgb z y flag)");
    m = good;
    m.fields[3].datatype = 9;
    expect_error(m, "unknown datatype 9");
    m = good;
    m.fields[2].offset = 20;  // float64 past point_step 22
    expect_error(m, "beyond point_step");
    m = good;
    m.fields[4].name = "z";
    expect_error(m, "appears twice");
    m = good;
    m.row_step = 30;
    expect_error(m, "row_step 30");
    EXPECT_THROW(io::ToPointCloud2(FullCloud(2, 1), {.point_alignment = 0}), InvalidArgument);
}

TEST(PointCloud2, CdrAndRos1SerialisationsRoundTrip) {
    auto msg = io::ToPointCloud2(FullCloud(3, 2));
    msg.stamp = {1700000000, 123456789};
    msg.frame_id = "camera_rgb_optical_frame";
    msg.seq = 42;
    for (const bool big : {false, true}) {
        const auto bytes = io::EncodePointCloud2Cdr(msg, big);
        EXPECT_EQ(bytes[1], big ? 0 : 1);
        auto back = io::DecodePointCloud2Cdr(bytes, "cdr");
        EXPECT_EQ(back.stamp, msg.stamp);
        EXPECT_EQ(back.frame_id, msg.frame_id);
        EXPECT_EQ(back.fields, msg.fields);
        EXPECT_EQ(back.data, msg.data);
        EXPECT_EQ(back.row_step, msg.row_step);
        EXPECT_EQ(back.height, 2u);
    }
    const auto ros1 = io::EncodePointCloud2Ros1(msg);
    const auto back = io::DecodePointCloud2Ros1(ros1, "ros1");
    EXPECT_EQ(back.seq, 42u);
    EXPECT_EQ(back.stamp, msg.stamp);
    EXPECT_EQ(back.frame_id, msg.frame_id);
    EXPECT_EQ(back.fields, msg.fields);
    EXPECT_EQ(back.data, msg.data);
}

TEST(PointCloud2, TruncatedOrForeignBytesAreFormatErrors) {
    auto msg = io::ToPointCloud2(FullCloud(3, 1));
    auto cdr = io::EncodePointCloud2Cdr(msg);
    for (const std::size_t cut :
         {std::size_t{2}, std::size_t{10}, cdr.size() / 2, cdr.size() - 1}) {
        const std::vector<std::uint8_t> part(cdr.begin(), cdr.begin() + cut);
        EXPECT_THROW(io::DecodePointCloud2Cdr(part, "cut"), FormatError) << cut;
    }
    auto ros1 = io::EncodePointCloud2Ros1(msg);
    ros1.resize(ros1.size() - 3);
    EXPECT_THROW(io::DecodePointCloud2Ros1(ros1, "cut"), FormatError);
    // A std_msgs/String is not a point cloud.
    io::CdrWriter w;
    w.String("Hello, world!");
    EXPECT_THROW(io::DecodePointCloud2Cdr(w.bytes(), "string"), FormatError);
    EXPECT_EQ(io::DecodeStringCdr(w.bytes(), "string"), "Hello, world!");
    // Parameter-list CDR is refused by name.
    std::vector<std::uint8_t> pl = {0x00, 0x03, 0, 0, 0, 0, 0, 0};
    try {
        io::DecodePointCloud2Cdr(pl, "pl");
        ADD_FAILURE();
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("0x0003"), std::string::npos);
    }
}

TEST(Cdr, AlignsEachPrimitiveToItsSizeFromTheEndOfTheHeader) {
    io::CdrWriter w;
    w.U8(7);
    w.F64(2.5);
    w.U16(9);
    w.U32(11);
    ASSERT_EQ(w.bytes().size(), 4u + 8 + 8 + 2 + 2 + 4);
    io::CdrReader r(w.bytes(), "aligned");
    EXPECT_EQ(r.U8(), 7);
    EXPECT_EQ(r.F64(), 2.5);
    EXPECT_EQ(r.position(), 16u);
    EXPECT_EQ(r.U16(), 9);
    EXPECT_EQ(r.U32(), 11u);
    EXPECT_EQ(r.remaining(), 0u);
    EXPECT_THROW(r.U8(), FormatError);
    // CDR2 aligns 8-byte values to 4 only.
    std::vector<std::uint8_t> cdr2 = {0x00, 0x07, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 4, 0x40};
    io::CdrReader r2(cdr2, "cdr2");
    EXPECT_EQ(r2.U8(), 1);
    EXPECT_EQ(r2.F64(), 2.5);
}

TEST(MessageStamp, NanosecondsAndText) {
    const auto s = io::MessageStamp::FromNanoseconds(1585866235112411371LL);
    EXPECT_EQ(s.sec, 1585866235);
    EXPECT_EQ(s.nanosec, 112411371u);
    EXPECT_EQ(s.ToString(), "1585866235.112411371");
    EXPECT_EQ(io::MessageStamp::FromNanoseconds(5).ToString(), "0.000000005");
    EXPECT_EQ(io::MessageStamp::FromNanoseconds(s.Nanoseconds()), s);
}

}  // namespace
}  // namespace multicue

namespace multicue {
namespace {

TEST(DepthImage, BackProjectsThroughThePinholeModel) {
    io::DepthImage depth{4, 3, std::vector<float>(12, 0.0f)};
    depth.depth[1 * 4 + 2] = 2.0f;  // u 2, v 1
    depth.depth[2 * 4 + 0] = 1.0f;  // u 0, v 2
    depth.depth[0] = std::numeric_limits<float>::quiet_NaN();
    const io::CameraIntrinsics k{.fx = 100, .fy = 50, .cx = 2, .cy = 1};
    std::vector<Color> colors(12, Color{1, 2, 3, 255});
    const PointCloud c = io::DepthToCloud(depth, k, colors);
    EXPECT_TRUE(c.IsOrganized());
    EXPECT_EQ(c.width, 4u);
    EXPECT_EQ(c.CountFinite(), 2u);
    EXPECT_TRUE(c.At(2, 1).isApprox(Eigen::Vector3f(0, 0, 2)));
    EXPECT_TRUE(c.At(0, 2).isApprox(Eigen::Vector3f(-0.02f, 0.02f, 1.0f)));
    EXPECT_EQ(c.colors.size(), 12u);
    EXPECT_THROW(io::DepthToCloud(depth, {.fx = 0, .fy = 1}), InvalidArgument);
    EXPECT_THROW(io::DepthToCloud(depth, k, std::vector<Color>(5)), InvalidArgument);
    depth.depth.pop_back();
    EXPECT_THROW(io::DepthToCloud(depth, k), InvalidArgument);
    EXPECT_TRUE(io::DepthToCloud(io::DepthImage{}, k).empty());
}

}  // namespace
}  // namespace multicue
