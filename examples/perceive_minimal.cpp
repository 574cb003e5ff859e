// A minimal program using the multicue library: read a point cloud, run the table-top pipeline and
// print each object's category and size.
//
//   perceive_minimal scene.pcd [report.html]

#include <cstdio>
#include <exception>
#include <string>

#include "multicue/io/point_cloud_io.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_report.hpp"

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s CLOUD.pcd [REPORT.html]\n", argv[0]);
        return 2;
    }
    try {
        const multicue::PointCloud cloud = multicue::io::ReadPointCloud(argv[1]);
        const multicue::PerceiveResult result = multicue::Perceive(cloud, {});
        std::printf("support plane: %s, %zu objects\n", result.support.found ? "found" : "none",
                    result.objects.size());
        for (const auto& object : result.objects) {
            const auto& e = object.category.extents;
            std::printf("  #%d %-8s p=%.2f  %5zu points  %.0f x %.0f x %.0f mm\n", object.id,
                        std::string(multicue::CategoryName(object.category.category)).c_str(),
                        object.category.confidence, object.indices.size(), 1000 * e.x(),
                        1000 * e.y(), 1000 * e.z());
        }
        if (argc > 2) multicue::WritePerceiveReport(argv[2], cloud, result, argv[1]);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
