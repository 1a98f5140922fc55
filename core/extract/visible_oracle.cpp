#include "core/extract/visible_oracle.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "core/check.h"
#include "core/kernel/iso.h"
#include "core/kernel/mc_tables.h"

namespace vdiso {

VisibleSurfaceOracle visibleSurfaceOracle(BrickSource& source, const Camera& camera,
                                          std::span<const float> depth, double iso) {
    VDISO_CHECK_EQ(depth.size(), size_t(camera.width) * size_t(camera.height));
    const VolumeInfo& v = source.volume();
    const BrickLayout& layout = source.layout();
    const PixelProjector pixels(camera);
    // Visible cells, grouped by brick: brick -> its cells' coordinates inside the brick.
    std::map<int64_t, std::vector<std::array<int, 3>>> cellsOfBrick;
    VisibleSurfaceOracle oracle;
    std::vector<int64_t> seen;
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            const float d = depth[size_t(y) * size_t(camera.width) + size_t(x)];
            if (!(d < 1.0f)) continue;
            ++oracle.pixels;
            const glm::dvec3 w = pixels.unproject({x + 0.5, y + 0.5, double(d)});
            int64_t cell[3];
            for (int a = 0; a < 3; ++a)
                cell[a] = std::clamp<int64_t>(int64_t(std::floor((w[a] - v.origin[a]) / v.spacing[a])),
                                              0, v.dims[a] - 2);
            seen.push_back((cell[2] * (v.dims[1] - 1) + cell[1]) * (v.dims[0] - 1) + cell[0]);
        }
    std::sort(seen.begin(), seen.end());
    seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
    oracle.cells = seen.size();
    for (int64_t id : seen) {
        const int64_t cx = id % (v.dims[0] - 1), cy = (id / (v.dims[0] - 1)) % (v.dims[1] - 1),
                      cz = id / ((v.dims[0] - 1) * (v.dims[1] - 1));
        const int64_t B = layout.brickSize;
        const int64_t brick = layout.brickId(cx / B, cy / B, cz / B);
        cellsOfBrick[brick].push_back({int(cx % B), int(cy % B), int(cz % B)});
    }
    oracle.bricks = cellsOfBrick.size();
    const int side = layout.side();
    // Not a structured binding: the lambda below captures `cells`, which clang before 16
    // refuses for bindings (C++20 allows it).
    for (const auto& entry : cellsOfBrick) {
        const int64_t brick = entry.first;
        const auto& cells = entry.second;
        const BrickHandle handle = source.acquire(brick);
        visitScalarType(v.type, [&](auto zero) {
            using T = decltype(zero);
            const T* s = handle.samplesAs<T>();
            for (const auto& c : cells) {
                int caseIndex = 0;
                for (int k = 0; k < 8; ++k) {
                    const size_t at = (size_t(c[2] + kCornerOffset[k][2] + kGhostBefore) * side +
                                       size_t(c[1] + kCornerOffset[k][1] + kGhostBefore)) * side +
                                      size_t(c[0] + kCornerOffset[k][0] + kGhostBefore);
                    caseIndex |= int(isAbove(double(s[at]), iso)) << k;
                }
                oracle.triangles += mcTriangleCase(caseIndex).triangleCount;
            }
        });
    }
    return oracle;
}

}  // namespace vdiso
