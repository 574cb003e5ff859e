// PointCloud2 interoperability with PCL: every layout pcl::toROSMsg writes (pcl_conversions)
// is read by FromPointCloud2 with PCL's values, and what ToPointCloud2 writes from it is read
// back by pcl::fromROSMsg with the same values.

#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "multicue/io/point_cloud2.hpp"
#include "pcl_layouts.hpp"

namespace multicue {
namespace {

void ExpectSameFloats(const std::vector<float>& a, const std::vector<float>& b,
                      const std::string& what) {
    ASSERT_EQ(a.size(), b.size()) << what;
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (std::isnan(a[i])) {
            EXPECT_TRUE(std::isnan(b[i])) << what << " " << i;
        } else {
            EXPECT_EQ(a[i], b[i]) << what << " " << i;
        }
    }
}

/// The PCL values of a multicue cloud read from PCL's message.
test::PclValues ValuesOf(const PointCloud& c, const std::vector<std::string>& extra_names) {
    test::PclValues v;
    for (const auto& p : c.points) v.xyz.insert(v.xyz.end(), {p.x(), p.y(), p.z()});
    for (const auto& n : c.normals) v.normals.insert(v.normals.end(), {n.x(), n.y(), n.z()});
    v.curvature = c.curvature;
    v.intensity = c.intensity;
    v.label = c.labels;
    for (const auto& col : c.colors) v.rgba.insert(v.rgba.end(), {col.r, col.g, col.b, col.a});
    for (std::size_t i = 0; i < c.size(); ++i) {
        for (const auto& name : extra_names) {
            if (name == "confidence") {
                v.extra.push_back(c.confidence.at(i));
                continue;
            }
            const ExtraField* f = c.FindExtraField(name);
            if (f == nullptr || f->type != 'F' || f->size != 4) {
                ADD_FAILURE() << "no float field " << name;
                return v;
            }
            float x;
            std::memcpy(&x, f->data.data() + 4 * i, 4);
            v.extra.push_back(x);
        }
    }
    return v;
}

void ExpectSameValues(const test::PclValues& a, const test::PclValues& b, const std::string& what) {
    ExpectSameFloats(a.xyz, b.xyz, what + " xyz");
    ExpectSameFloats(a.normals, b.normals, what + " normals");
    ExpectSameFloats(a.curvature, b.curvature, what + " curvature");
    ExpectSameFloats(a.intensity, b.intensity, what + " intensity");
    EXPECT_EQ(a.label, b.label) << what;
    EXPECT_EQ(a.rgba, b.rgba) << what;
    ExpectSameFloats(a.extra, b.extra, what + " extra");
}

TEST(PclPointCloud2, ReadsEveryLayoutPclWritesAndPclReadsOursBack) {
    const auto layouts = test::PclLayouts();
    ASSERT_GE(layouts.size(), 15u);
    for (const auto& layout : layouts) {
        SCOPED_TRACE(layout.type);
        const PointCloud cloud = io::FromPointCloud2(layout.message, layout.type);
        EXPECT_EQ(cloud.IsOrganized(), layout.organized);
        ExpectSameValues(layout.values, ValuesOf(cloud, layout.values.extra_names),
                         "multicue reading PCL's " + layout.type);

        const bool rgba = layout.message.FindField("rgba") != nullptr;
        for (const bool big : {false}) {
            const auto ours =
                io::ToPointCloud2(cloud, {.big_endian = big, .point_alignment = 16, .rgba = rgba});
            auto back = test::PclRead(layout.type, ours);
            back.extra_names = layout.values.extra_names;
            ExpectSameValues(layout.values, back, "PCL reading multicue's " + layout.type);
        }
    }
}

}  // namespace
}  // namespace multicue
