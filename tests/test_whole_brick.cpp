// A full extraction takes a brick whole, in rows (BrickKernel::emitBrick), where its rows of
// corners fit a word: the same triangles, vertices and normals, bit for bit, as the meta-cell
// kernel makes over every meta-cell, in another order; on every sample type, with samples that
// are not finite, and meta-cells that do not divide the brick.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <vector>

#include "core/kernel/brick_extractor.h"
#include "core/kernel/edge_vertex_map.h"
#include "tests/extract_test_util.h"

namespace vdiso {
namespace {

using Corner = std::array<uint32_t, 6>;  // position and normal, as bits
using Triangle = std::array<Corner, 3>;

// The triangles of `mesh`, each turned to start at its least corner (orientation kept), sorted.
std::vector<Triangle> triangleSet(const TriangleMesh& mesh) {
    std::vector<Triangle> out;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        Triangle tri;
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = mesh.indices[3 * t + size_t(k)] - mesh.firstVertex;
            std::memcpy(tri[size_t(k)].data(), &mesh.positions[v], 12);
            std::memcpy(tri[size_t(k)].data() + 3, &mesh.normals[v], 12);
        }
        std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
        out.push_back(tri);
    }
    std::sort(out.begin(), out.end());
    return out;
}

TEST(WholeBrick, MakesWhatTheMetaCellsMake) {
    for (int brickSize : {8, 13, 32})
        for (int metaCellSize : {1, 3, 4})
            for (ScalarType type : {ScalarType::U8, ScalarType::I16, ScalarType::U16, ScalarType::F32}) {
                const Dims3 dims{2 * brickSize + 5, brickSize + 3, brickSize + 7};
                test::MemoryBrickSource source(dims, type, brickSize, [&](int64_t x, int64_t y, int64_t z) {
                    if (type == ScalarType::F32 && (x * 3 + y + z) % 17 == 0) return (y % 2) ? double(NAN) : double(-INFINITY);
                    return 20.0 + 9.0 * std::sin(0.4 * double(x)) * std::cos(0.3 * double(y)) + 6.0 * std::sin(0.5 * double(z));
                });
                BrickExtractor whole(source.volume(), source.layout(), metaCellSize),
                    parts(source.volume(), source.layout(), metaCellSize);
                ASSERT_TRUE(whole.wholeBricks());
                std::vector<uint32_t> every(size_t(parts.metaCellsPerBrick()));
                for (size_t m = 0; m < every.size(); ++m) every[m] = uint32_t(m);
                TriangleMesh a, b;
                EdgeVertexMap seamsA, seamsB;
                for (int64_t id = 0; id < source.layout().brickCount(); ++id) {
                    const BrickHandle brick = source.acquire(id);
                    whole.extractBrick(id, brick.samples(), 20.5, a, seamsA);
                    parts.extractMetaCells(id, brick.samples(), 20.5, every, b, seamsB);
                }
                SCOPED_TRACE(::testing::Message() << "bricks of " << brickSize << ", meta-cells of " << metaCellSize
                                                  << ", type " << int(type));
                ASSERT_GT(a.triangleCount(), 200u);
                EXPECT_EQ(a.vertexCount(), b.vertexCount());
                EXPECT_EQ(a.triangleCount(), b.triangleCount());
                EXPECT_TRUE(triangleSet(a) == triangleSet(b));
                EXPECT_EQ(whole.counters().cellsActive, parts.counters().cellsActive);
            }
}

}  // namespace
}  // namespace vdiso
