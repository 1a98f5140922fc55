// Generates the marching-cubes tables from the cube's faces.
//
// On each face the surface is a set of segments joining crossed edges of that face. Walking
// the face's boundary counter-clockwise as seen from outside the cube, the corners fall into
// cyclic runs of above corners; each run gets its own segment, from the edge where the walk
// enters the run to the edge where it leaves it. One segment per run is exactly the ambiguous
// face rule (diagonal above corners are two runs, so they are separated), and the direction
// puts the below side on the segment's left seen from outside, which is what a polygon whose
// counter-clockwise normal points to the below side needs on its boundary (its inside, the
// cube's interior, lies to the left of each boundary edge seen along the normal).
//
// Each crossed edge lies on two faces, whose boundary walks run along it in opposite
// directions: it enters a run on one face and leaves one on the other. So every crossed edge
// has exactly one outgoing and one incoming segment, and following the segments splits the
// crossed edges into disjoint directed loops: the polygons.
#include "core/kernel/mc_tables.h"

#include <array>

#include "core/check.h"

namespace vdiso {
namespace {

// Face corners counter-clockwise seen from outside the cube. Face 2a + s is the face where
// axis a has coordinate s.
constexpr std::array<std::array<int, 4>, 6> faceCorners() {
    std::array<std::array<int, 4>, 6> faces{};
    for (int axis = 0; axis < 3; ++axis) {
        // (u, v, axis) is right-handed, so (0,0) (1,0) (1,1) (0,1) in (u, v) turns
        // counter-clockwise seen from +axis.
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int side = 0; side < 2; ++side) {
            for (int i = 0; i < 4; ++i) {
                // Seen from -axis (side 0) the same order turns clockwise: walk it backwards.
                const int k = side == 1 ? i : (4 - i) % 4;
                faces[2 * axis + side][i] = (side << axis) | (uv[k][0] << u) | (uv[k][1] << v);
            }
        }
    }
    return faces;
}

constexpr int edgeBetween(int a, int b) {
    for (int e = 0; e < kMcEdgeCount; ++e) {
        if ((kEdgeCorners[e][0] == a && kEdgeCorners[e][1] == b) ||
            (kEdgeCorners[e][0] == b && kEdgeCorners[e][1] == a))
            return e;
    }
    return -1;
}

// Twice the midpoint of an edge: integer coordinates, so the geometry below is exact.
struct Point2 {
    int x, y, z;
};

constexpr Point2 edgeMidpoint2(int e) {
    const int8_t* a = kCornerOffset[kEdgeCorners[e][0]];
    const int8_t* b = kCornerOffset[kEdgeCorners[e][1]];
    return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}

constexpr Point2 operator-(Point2 a, Point2 b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
constexpr Point2 cross(Point2 a, Point2 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
constexpr int dot(Point2 a, Point2 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

// Whether two edges lie on a common face of the cube.
constexpr bool shareFace(int e, int f) {
    const int corners[4] = {kEdgeCorners[e][0], kEdgeCorners[e][1], kEdgeCorners[f][0],
                            kEdgeCorners[f][1]};
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
            bool onFace = true;
            for (int c : corners) onFace = onFace && ((c >> axis) & 1) == side;
            if (onFace) return true;
        }
    }
    return false;
}

// Unit step along crossed edge e from its above corner to its below one.
constexpr Point2 belowward(int caseIndex, int e) {
    const int sign = ((caseIndex >> kEdgeCorners[e][0]) & 1) ? 1 : -1;
    const int axis = mcEdgeAxis(e);
    return {axis == 0 ? sign : 0, axis == 1 ? sign : 0, axis == 2 ? sign : 0};
}

// Where to start the fan of the loop of n edges (the polygon is rotated to start there).
// Polygons of six or seven vertices are non-planar and may be concave, and a careless root
// gives fan triangles that fold over or lie flat in a cube face. So, with vertices at the edge
// midpoints, a root is acceptable when
//  - no fan diagonal joins two edges of one face (it would lie in that face, where the
//    neighbouring cell could emit it too), and
//  - no triangle faces against a crossed edge it touches (its normal has no component from
//    the below corner towards the above one): the surface crosses each edge once, not in a
//    fold around it;
// and among acceptable roots the thinnest fan triangle (its area along the polygon's Newell
// normal) is as fat as possible, ties going to the earliest. Returns -1 when no root is
// acceptable and keeps every triangle facing the polygon's normal (never, static_assert below).
constexpr int fanRoot(int caseIndex, const int* loop, int n) {
    Point2 normal{0, 0, 0};
    for (int i = 0; i < n; ++i) {
        const Point2 a = edgeMidpoint2(loop[i]), b = edgeMidpoint2(loop[(i + 1) % n]);
        const Point2 c = cross(a, b);
        normal = {normal.x + c.x, normal.y + c.y, normal.z + c.z};
    }
    int bestRoot = -1, bestScore = 0;
    for (int root = 0; root < n; ++root) {
        bool ok = true;
        int score = 1 << 30;
        for (int i = 1; i + 1 < n; ++i) {
            const int a = loop[root], b = loop[(root + i) % n], c = loop[(root + i + 1) % n];
            if (i >= 2 && shareFace(a, b)) ok = false;
            const Point2 pa = edgeMidpoint2(a);
            const Point2 triangleNormal = cross(edgeMidpoint2(b) - pa, edgeMidpoint2(c) - pa);
            for (int e : {a, b, c}) {
                if (dot(triangleNormal, belowward(caseIndex, e)) < 0) ok = false;
            }
            const int area = dot(triangleNormal, normal);
            score = area < score ? area : score;
        }
        if (ok && score > bestScore) {
            bestRoot = root;
            bestScore = score;
        }
    }
    return bestRoot;
}

// The polygons of case `caseIndex` with the ambiguous faces in `joinAbove` (bit f: face f, as
// faceCorners() numbers them) cut the other way: their below corners separated and the above
// ones joined across the face. There the walk makes one segment per run of below corners,
// from the edge where it leaves the run to the edge where it enters it: each crossed edge
// keeps its role (the start of one segment, the end of another) on that face, so the loops
// still chain, and the below corner is still on each segment's left. Returns false when the
// segments do not chain (never: static_assert below for joinAbove 0, tests for the rest).
constexpr bool buildPolygons(int caseIndex, int joinAbove, McPolygonCase& poly, McTriangleCase* tri, int& maxVertices,
                             bool& fansOk) {
    constexpr std::array<std::array<int, 4>, 6> faces = faceCorners();
    auto above = [&](int corner) { return ((caseIndex >> corner) & 1) != 0; };
    // next[e]: the edge the segment leaving crossed edge e goes to.
    int next[kMcEdgeCount] = {-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1};
    int incoming[kMcEdgeCount] = {};
    bool consistent = true;
    for (int f = 0; f < 6; ++f) {
        const std::array<int, 4>& q = faces[size_t(f)];
        const bool ambiguous = above(q[0]) == above(q[2]) && above(q[1]) == above(q[3]) && above(q[0]) != above(q[1]);
        const bool aroundBelow = ambiguous && ((joinAbove >> f) & 1);
        for (int i = 0; i < 4; ++i) {
            // Runs of above corners (or, cut the other way, of below ones), entered at edge i.
            const bool runKind = !aroundBelow;
            if (above(q[i]) == runKind || above(q[(i + 1) % 4]) != runKind) continue;
            int j = (i + 1) % 4;
            while (above(q[(j + 1) % 4]) == runKind) j = (j + 1) % 4;
            const int enter = edgeBetween(q[i], q[(i + 1) % 4]);
            const int leave = edgeBetween(q[j], q[(j + 1) % 4]);
            const int from = aroundBelow ? leave : enter, to = aroundBelow ? enter : leave;
            if (next[from] != -1) consistent = false;
            next[from] = to;
            ++incoming[to];
        }
    }
    for (int e = 0; e < kMcEdgeCount; ++e) {
        const bool isCrossed = above(kEdgeCorners[e][0]) != above(kEdgeCorners[e][1]);
        if ((next[e] != -1) != isCrossed || incoming[e] != int(isCrossed)) consistent = false;
    }
    if (!consistent) return false;

    // Chain the segments into loops, each found from its smallest edge id, then fan them.
    poly = McPolygonCase{};
    if (tri) *tri = McTriangleCase{};
    bool visited[kMcEdgeCount] = {};
    int edgeCount = 0;
    for (int start = 0; start < kMcEdgeCount; ++start) {
        if (next[start] == -1 || visited[start]) continue;
        int loop[kMcEdgeCount] = {};
        int n = 0;
        for (int e = start; !visited[e]; e = next[e]) {
            visited[e] = true;
            loop[n++] = e;
        }
        int root = fanRoot(caseIndex, loop, n);
        if (root < 0) {
            fansOk = false;
            root = 0;
        }
        for (int i = 0; i < n; ++i) poly.edges[edgeCount + i] = uint8_t(loop[(root + i) % n]);
        const uint8_t* v = poly.edges + edgeCount;
        edgeCount += n;
        if (poly.polygonCount < kMcMaxPolygons) poly.vertexCount[poly.polygonCount] = uint8_t(n);
        ++poly.polygonCount;
        maxVertices = n > maxVertices ? n : maxVertices;
        for (int i = 1; tri && i + 1 < n; ++i) {
            if (tri->triangleCount < kMcMaxTriangles) {
                uint8_t* w = tri->edges + 3 * tri->triangleCount;
                w[0] = v[0];
                w[1] = v[i];
                w[2] = v[i + 1];
            }
            ++tri->triangleCount;
        }
    }
    return true;
}

struct Tables {
    std::array<McPolygonCase, kMcCaseCount> polygons{};
    std::array<McTriangleCase, kMcCaseCount> triangles{};
    std::array<uint16_t, kMcCaseCount> crossed{};
    // What the generator needed, to check the header's bounds against.
    int maxPolygons = 0, maxPolygonVertices = 0, maxTriangles = 0;
    bool consistent = true;  // every crossed edge has one segment in and one out
    bool fansOk = true;      // every polygon has a root fanRoot() accepts
};

constexpr Tables generate() {
    Tables t;
    for (int caseIndex = 0; caseIndex < kMcCaseCount; ++caseIndex) {
        uint16_t crossed = 0;
        for (int e = 0; e < kMcEdgeCount; ++e) {
            if (((caseIndex >> kEdgeCorners[e][0]) & 1) != ((caseIndex >> kEdgeCorners[e][1]) & 1))
                crossed |= uint16_t(1u << e);
        }
        t.crossed[caseIndex] = crossed;
        McPolygonCase& poly = t.polygons[caseIndex];
        McTriangleCase& tri = t.triangles[caseIndex];
        if (!buildPolygons(caseIndex, 0, poly, &tri, t.maxPolygonVertices, t.fansOk)) t.consistent = false;
        t.maxPolygons = poly.polygonCount > t.maxPolygons ? poly.polygonCount : t.maxPolygons;
        t.maxTriangles = tri.triangleCount > t.maxTriangles ? tri.triangleCount : t.maxTriangles;
    }
    return t;
}

constexpr Tables kTables = generate();

static_assert(kTables.consistent, "face segments do not chain into loops");
static_assert(kTables.fansOk, "some polygon has no acceptable fan");
static_assert(kTables.maxPolygons == kMcMaxPolygons, "kMcMaxPolygons is not what the cube gives");
static_assert(kTables.maxPolygonVertices == kMcMaxPolygonVertices,
              "kMcMaxPolygonVertices is not what the cube gives");
static_assert(kTables.maxTriangles == kMcMaxTriangles,
              "kMcMaxTriangles is not what the cube gives");

}  // namespace

const McPolygonCase& mcPolygonCase(int caseIndex) {
    VDISO_CHECK_LT(unsigned(caseIndex), unsigned(kMcCaseCount));
    return kTables.polygons[caseIndex];
}

const McTriangleCase& mcTriangleCase(int caseIndex) {
    VDISO_CHECK_LT(unsigned(caseIndex), unsigned(kMcCaseCount));
    return kTables.triangles[caseIndex];
}

bool mcPolygonsJoined(int caseIndex, int joinAbove, McPolygonCase& out) {
    VDISO_CHECK_LT(unsigned(caseIndex), unsigned(kMcCaseCount));
    int maxVertices = 0;
    bool fansOk = true;
    return buildPolygons(caseIndex, joinAbove & mcAmbiguousFaces(caseIndex), out, nullptr, maxVertices, fansOk);
}

int mcAmbiguousFaces(int caseIndex) {
    constexpr std::array<std::array<int, 4>, 6> faces = faceCorners();
    int mask = 0;
    for (int f = 0; f < 6; ++f) {
        const std::array<int, 4>& q = faces[size_t(f)];
        const int a = caseIndex >> q[0] & 1, b = caseIndex >> q[1] & 1, c = caseIndex >> q[2] & 1, d = caseIndex >> q[3] & 1;
        if (a == c && b == d && a != b) mask |= 1 << f;
    }
    return mask;
}

bool mcEdgesShareFace(int e, int f) {
    VDISO_CHECK_LT(unsigned(e), unsigned(kMcEdgeCount));
    VDISO_CHECK_LT(unsigned(f), unsigned(kMcEdgeCount));
    return shareFace(e, f);
}

const std::array<std::array<int, 4>, 6>& mcFaceCorners() {
    static constexpr std::array<std::array<int, 4>, 6> faces = faceCorners();
    return faces;
}

uint16_t mcCrossedEdges(int caseIndex) {
    VDISO_CHECK_LT(unsigned(caseIndex), unsigned(kMcCaseCount));
    return kTables.crossed[caseIndex];
}

}  // namespace vdiso
