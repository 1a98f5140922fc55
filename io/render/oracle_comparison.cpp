#include "io/render/oracle_comparison.h"

#include "core/extract/extract_full.h"
#include "io/render/renderer.h"

namespace vdiso {

OracleComparison compareWithOracle(BrickSource& source, const Camera& camera, double iso,
                                   int metaCellSize, int threads) {
    TriangleMesh full;
    extractOctree(source, {iso, metaCellSize, threads}, full);
    const RenderResult r = renderSurface(full, PointSet{}, camera);
    OracleComparison c;
    c.oracle = visibleSurfaceOracle(source, camera, r.depth, iso);
    c.fullTriangles = full.triangleCount();
    return c;
}

}  // namespace vdiso
