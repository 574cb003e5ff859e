#include <algorithm>
#include <cmath>
#include <limits>

#include "multicue/mapping/front_edges.hpp"
#include "multicue/mapping/front_grid_internal.hpp"
#include "multicue/mapping/fronts.hpp"

namespace multicue::mapping {

using namespace front_grid_internal;

void ExtendFrontsToOutlines(const PointCloud& cloud, const RoomFrame& frame, const RoomStructure& s,
                            const std::vector<Fixture>& fixtures, const FrontEvidence& ev,
                            std::vector<Front>& fronts, const FrontEdgeParams& p) {
    p.Validate();
    CheckEvidence(ev, cloud.size());
    if (cloud.empty() || fronts.empty()) return;
    const std::vector<std::uint8_t> is_fixture = FixturePoints(cloud.size(), fixtures);
    // Which front holds each point now: extensions take no point of another front.
    std::vector<std::int32_t> owner(cloud.size(), -1);
    for (std::size_t r = 0; r < fronts.size(); ++r) {
        for (const Index i : fronts[r].indices) owner[i] = static_cast<std::int32_t>(r);
    }
    const std::vector<Indices> face_points = FacePoints(cloud.size(), s, ev);
    for (std::size_t f = 0; f < s.components.size(); ++f) {
        std::vector<std::size_t> mine;
        for (std::size_t r = 0; r < fronts.size(); ++r) {
            if (fronts[r].face == static_cast<int>(f)) mine.push_back(r);
        }
        if (mine.empty()) continue;
        const PlanarComponent& face = s.components[f];
        if (face_points[f].empty()) continue;
        OutlineGrid g = BuildGrid(cloud, frame, face, face_points[f], ev, is_fixture, p);
        if (g.nu == 0) continue;
        MaskFixtures(g, cloud, frame, face, static_cast<int>(f), fixtures, p);
        const int steps = static_cast<int>(std::ceil(p.max_extend / g.cell));
        std::vector<std::pair<Eigen::Vector2f, Eigen::Vector2f>> grown(mine.size());
        for (std::size_t k = 0; k < mine.size(); ++k) {
            const Front& fr = fronts[mine[k]];
            Eigen::Vector2f lo = fr.min, hi = fr.max;
            const int u0 = std::clamp(g.U(lo.x()), 0, g.nu - 1);
            const int u1 = std::clamp(g.U(hi.x()), 0, g.nu - 1);
            const int v0 = std::clamp(g.V(lo.y()), 0, g.nv - 1);
            const int v1 = std::clamp(g.V(hi.y()), 0, g.nv - 1);
            if (const int l = FindSideWithin(g, true, u0, -1, v0, v1, steps, p); l >= 0)
                lo.x() = std::min(lo.x(), g.UAt(l));
            if (const int r = FindSideWithin(g, true, u1, 1, v0, v1, steps, p); r >= 0)
                hi.x() = std::max(hi.x(), g.UAt(r));
            if (const int b = FindSideWithin(g, false, v0, -1, u0, u1, steps, p); b >= 0)
                lo.y() = std::min(lo.y(), g.VAt(b));
            if (const int t = FindSideWithin(g, false, v1, 1, u0, u1, steps, p); t >= 0)
                hi.y() = std::max(hi.y(), g.VAt(t));
            // Never into another front's rectangle.
            for (const std::size_t o : mine) {
                if (o == mine[k]) continue;
                const Eigen::Vector2f olo = fronts[o].min, ohi = fronts[o].max;
                const bool rows = olo.y() < fr.max.y() && ohi.y() > fr.min.y();
                const bool cols = olo.x() < fr.max.x() && ohi.x() > fr.min.x();
                if (rows && ohi.x() <= fr.min.x()) lo.x() = std::max(lo.x(), ohi.x());
                if (rows && olo.x() >= fr.max.x()) hi.x() = std::min(hi.x(), olo.x());
                if (cols && ohi.y() <= fr.min.y()) lo.y() = std::max(lo.y(), ohi.y());
                if (cols && olo.y() >= fr.max.y()) hi.y() = std::min(hi.y(), olo.y());
            }
            grown[k] = {lo, hi};
        }
        for (std::size_t k = 0; k < mine.size(); ++k) {
            Front& fr = fronts[mine[k]];
            const auto& [lo, hi] = grown[k];
            for (const Index i : face.indices) {
                if (owner[i] >= 0 || is_fixture[i]) continue;
                const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
                if ((q.array() < lo.array()).any() || (q.array() > hi.array()).any()) continue;
                owner[i] = static_cast<std::int32_t>(mine[k]);
                fr.indices.push_back(i);
            }
            std::sort(fr.indices.begin(), fr.indices.end());
            SetFrontRectangle(fr, face, frame, lo, hi);
        }
    }
}

}  // namespace multicue::mapping
