#include "core/extract/image_strips.h"

#include <algorithm>

#include "core/kernel/iso.h"

namespace vdiso {

std::vector<int> stripColumns(const BrickSource& source, const Camera& camera, double iso, int strips, int column0,
                              int column1) {
    const BrickLayout& layout = source.layout();
    const VolumeInfo& volume = source.volume();
    const PixelProjector pixels(camera);
    std::vector<double> centres;
    const std::span<const BrickRange> ranges = source.brickRanges();
    for (int64_t id = 0; id < layout.brickCount(); ++id) {
        if (!rangeHoldsIso(ranges[size_t(id)].minValue, ranges[size_t(id)].maxValue, iso)) continue;
        const Dims3 c = layout.brickCoord(id);
        glm::dvec3 centre;
        for (int k = 0; k < 3; ++k)
            centre[k] = volume.origin[k] +
                        (double(c[k] * layout.brickSize) + 0.5 * layout.cellsOnAxis(k, c[k])) * volume.spacing[k];
        const glm::dvec3 s = pixels.project(centre);
        if (s.z >= 0.0 && s.z <= 1.0 && s.x >= column0 && s.x < column1) centres.push_back(s.x);
    }
    std::sort(centres.begin(), centres.end());
    std::vector<int> columns{column0};
    for (int k = 1; k < strips; ++k) {
        const int even = column0 + (column1 - column0) * k / strips;
        const int cut = centres.empty() ? even : int(centres[centres.size() * size_t(k) / size_t(strips)]);
        columns.push_back(std::clamp(cut, columns.back() + 1, column1 - (strips - k)));
    }
    columns.push_back(column1);
    return columns;
}

void coverOutsideStrip(OcclusionPyramid& pyramid, int column0, int column1) {
    for (int y = 0; y < pyramid.height(); ++y) {
        if (column0 > 0) pyramid.coverSpan(y, 0, column0 - 1);
        if (column1 < pyramid.width()) pyramid.coverSpan(y, column1, pyramid.width() - 1);
    }
    pyramid.propagate();
}

ExtractStats mergeStrips(std::vector<StripOutput>& outputs, TriangleMesh& mesh, PointSet& points,
                         int64_t firstCoarseBrick) {
    size_t vertices = 0, indices = 0;
    for (const StripOutput& part : outputs) {
        vertices += part.triangles.positions.size();
        indices += part.triangles.indices.size();
    }
    mesh.positions.reserve(mesh.positions.size() + vertices);
    mesh.normals.reserve(mesh.normals.size() + vertices);
    mesh.indices.reserve(mesh.indices.size() + indices);
    ExtractStats stats;
    std::vector<int64_t> acquired;
    for (StripOutput& part : outputs) {
        const uint32_t offset = mesh.nextVertex();
        const TriangleMesh& m = part.triangles;
        mesh.positions.insert(mesh.positions.end(), m.positions.begin(), m.positions.end());
        mesh.normals.insert(mesh.normals.end(), m.normals.begin(), m.normals.end());
        for (uint32_t v : m.indices) mesh.indices.push_back(v + offset);
        points.positions.insert(points.positions.end(), part.points.positions.begin(), part.points.positions.end());
        points.normals.insert(points.normals.end(), part.points.normals.begin(), part.points.normals.end());
        stats.addPart(part.stats);
        stats.triangles += part.stats.triangles;
        stats.vertices += part.stats.vertices;
        acquired.insert(acquired.end(), part.acquired.begin(), part.acquired.end());
    }
    std::sort(acquired.begin(), acquired.end());
    acquired.erase(std::unique(acquired.begin(), acquired.end()), acquired.end());
    stats.bricksActive = int64_t(acquired.size());
    stats.view.coarseBricks =
        int64_t(acquired.end() - std::lower_bound(acquired.begin(), acquired.end(), firstCoarseBrick));
    return stats;
}

}  // namespace vdiso
