// Marching-cubes case tables, generated from the cube's topology (not copied from a paper).
//
// Cell corner c (0..7) sits at offset (c & 1, (c >> 1) & 1, (c >> 2) & 1) from the cell's lowest
// corner (x is bit 0). The case index has bit c set when corner c's sample is above the
// isovalue (s > iso, core/kernel/iso.h). Edge e joins kEdgeCorners[e][0] (the lower corner) to
// kEdgeCorners[e][1]; edges 0-3 run along x, 4-7 along y, 8-11 along z; an edge is crossed
// when its two corners lie on different sides.
//
// Ambiguous faces (two diagonal corners above, the other two below) follow one rule
// everywhere: the above corners are separated, the below corners connect across the face. The
// rule reads only the face's four corners, so the two cells sharing a face cut it alike and
// the surface has no cracks. It is not complement-symmetric: case c and case 255 - c may differ.
//
// Polygon form (SAGE §3.2): each connected piece of surface in the cell is one polygon, given
// by its outline, a closed loop of edge ids; every crossed edge appears in exactly one polygon,
// exactly once; uncrossed edges never appear. Polygons may be non-planar and concave.
// Triangle form: the fan (v0, vi, vi+1) of each polygon, so both forms describe the same surface.
// Each polygon is rotated so that its fan is well shaped with vertices at the edge midpoints:
// no diagonal lies in a cube face, no triangle faces against a crossed edge it touches, and
// the thinnest triangle is as fat as possible.
// Orientation: seen from the side the normal points to, vertices run counter-clockwise, and
// that normal points from the above corners towards the below ones (along minus the gradient),
// as in core/mesh.h.
//
// The tables are built at compile time; the accessors are a bounds check and a load.
#pragma once

#include <array>
#include <cstdint>

#include "core/kernel/iso.h"

namespace vdiso {

constexpr int kMcCaseCount = 256;
constexpr int kMcEdgeCount = 12;

constexpr int8_t kCornerOffset[8][3] = {
    {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1},
};

constexpr uint8_t kEdgeCorners[kMcEdgeCount][2] = {
    {0, 1}, {2, 3}, {4, 5}, {6, 7},  // along x
    {0, 2}, {1, 3}, {4, 6}, {5, 7},  // along y
    {0, 4}, {1, 5}, {2, 6}, {3, 7},  // along z
};

// Axis (0 = x, 1 = y, 2 = z) an edge runs along.
constexpr int mcEdgeAxis(int edge) {
    return edge >> 2;
}

// Bounds the generator proves (mc_tables.cpp checks them with static_assert, and they are
// tight): at most 4 polygons per case (cases 0x69 and 0x96: four isolated above corners), at
// most 7 vertices per polygon (five above corners whose three below corners connect across
// ambiguous faces, e.g. 0x3d), at most 5 triangles per case. Over all 256 cases: 358
// polygons, 820 triangles.
constexpr int kMcMaxPolygons = 4;
constexpr int kMcMaxPolygonVertices = 7;
constexpr int kMcMaxTriangles = 5;

struct McPolygonCase {
    uint8_t polygonCount;
    uint8_t vertexCount[kMcMaxPolygons];  // of polygon 0, 1, ...; 0 past polygonCount
    uint8_t edges[kMcEdgeCount];          // edge ids of polygon 0, then polygon 1, ...
};

struct McTriangleCase {
    uint8_t triangleCount;
    uint8_t edges[3 * kMcMaxTriangles];  // three edge ids per triangle
};

const McPolygonCase& mcPolygonCase(int caseIndex);
const McTriangleCase& mcTriangleCase(int caseIndex);

// Bit e set when edge e is crossed in this case.
uint16_t mcCrossedEdges(int caseIndex);

// The six faces' corners, counter-clockwise seen from outside the cube; face 2a + s is the face
// where axis a has coordinate s.
const std::array<std::array<int, 4>, 6>& mcFaceCorners();
// Whether edges e and f lie on a common face of the cube.
bool mcEdgesShareFace(int e, int f);
// Bit f set when face f is ambiguous in this case (two diagonal corners above, two below).
int mcAmbiguousFaces(int caseIndex);
// The polygons of the case (as mcPolygonCase gives them) with the ambiguous faces of bit mask
// `joinAbove` cut the other way: their above corners joined across the face, the below ones
// separated (core/kernel/trilinear_cell.h decides which). mcPolygonsJoined(c, 0, p) gives
// mcPolygonCase(c). False when the face cuts do not chain into loops (never, tested).
bool mcPolygonsJoined(int caseIndex, int joinAbove, McPolygonCase& out);

// Case index of a cell from its eight corner samples, in corner order.
template <class T>
int mcCaseIndex(const T (&samples)[8], double iso) {
    int caseIndex = 0;
    for (int c = 0; c < 8; ++c) caseIndex |= int(isAbove(double(samples[c]), iso)) << c;
    return caseIndex;
}

}  // namespace vdiso
