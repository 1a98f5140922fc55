// The generated marching-cubes tables: structure of every case, the ambiguous-face rule,
// orientation, and watertight closed surfaces over whole volumes.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/kernel/mc_tables.h"

namespace vdiso {
namespace {

// The flat layout is part of the contract (meshoptimizer style: no pointers, no padding).
static_assert(sizeof(McPolygonCase) == 1 + kMcMaxPolygons + kMcEdgeCount);
static_assert(sizeof(McTriangleCase) == 1 + 3 * kMcMaxTriangles);
static_assert(kMcMaxTriangles <= kMcMaxPolygons * (kMcMaxPolygonVertices - 2));

struct Vec3 {
    double x = 0, y = 0, z = 0;
};
Vec3 operator+(Vec3 a, Vec3 b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
Vec3 operator-(Vec3 a, Vec3 b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
Vec3 operator*(double s, Vec3 a) {
    return {s * a.x, s * a.y, s * a.z};
}
double dot(Vec3 a, Vec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
Vec3 cross(Vec3 a, Vec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double length(Vec3 a) {
    return std::sqrt(dot(a, a));
}

bool isAboveIn(int caseIndex, int corner) {
    return (caseIndex >> corner) & 1;
}

Vec3 cornerPosition(int corner) {
    return {double(kCornerOffset[corner][0]), double(kCornerOffset[corner][1]),
            double(kCornerOffset[corner][2])};
}

Vec3 edgeMidpoint(int edge) {
    return 0.5 * (cornerPosition(kEdgeCorners[edge][0]) + cornerPosition(kEdgeCorners[edge][1]));
}

// Face 2 * axis + side holds the corners whose coordinate along axis is side.
bool cornerOnFace(int corner, int face) {
    return ((corner >> (face / 2)) & 1) == face % 2;
}
bool edgeOnFace(int edge, int face) {
    return cornerOnFace(kEdgeCorners[edge][0], face) && cornerOnFace(kEdgeCorners[edge][1], face);
}
int commonFace(int e, int f) {
    for (int face = 0; face < 6; ++face) {
        if (edgeOnFace(e, face) && edgeOnFace(f, face)) return face;
    }
    return -1;
}

// The polygons of a case as vectors of edge ids.
std::vector<std::vector<int>> polygonsOf(int caseIndex) {
    const McPolygonCase& pc = mcPolygonCase(caseIndex);
    std::vector<std::vector<int>> polygons;
    int k = 0;
    for (int p = 0; p < pc.polygonCount; ++p) {
        polygons.emplace_back(pc.edges + k, pc.edges + k + pc.vertexCount[p]);
        k += pc.vertexCount[p];
    }
    return polygons;
}

// Directed segments (consecutive loop vertices) of a case's polygons lying on one face.
std::set<std::pair<int, int>> faceSegments(int caseIndex, int face) {
    std::set<std::pair<int, int>> segments;
    for (const std::vector<int>& poly : polygonsOf(caseIndex)) {
        for (size_t i = 0; i < poly.size(); ++i) {
            const int a = poly[i], b = poly[(i + 1) % poly.size()];
            if (edgeOnFace(a, face) && edgeOnFace(b, face)) segments.insert({a, b});
        }
    }
    return segments;
}

Vec3 newellNormal(const std::vector<Vec3>& loop) {
    Vec3 n;
    for (size_t i = 0; i < loop.size(); ++i) n = n + cross(loop[i], loop[(i + 1) % loop.size()]);
    return n;
}

TEST(McTables, EmptyAndFullCasesHaveNoSurface) {
    for (int caseIndex : {0, 255}) {
        EXPECT_EQ(mcCrossedEdges(caseIndex), 0);
        EXPECT_EQ(mcPolygonCase(caseIndex).polygonCount, 0);
        EXPECT_EQ(mcTriangleCase(caseIndex).triangleCount, 0);
    }
}

TEST(McTables, EdgeAndCornerConventions) {
    for (int e = 0; e < kMcEdgeCount; ++e) {
        const int a = kEdgeCorners[e][0], b = kEdgeCorners[e][1];
        EXPECT_EQ(b - a, 1 << mcEdgeAxis(e)) << "edge " << e;  // lower corner first, one axis
        EXPECT_EQ(a & (1 << mcEdgeAxis(e)), 0);
    }
    for (int c = 0; c < 8; ++c) {
        EXPECT_EQ(kCornerOffset[c][0], c & 1);
        EXPECT_EQ(kCornerOffset[c][1], (c >> 1) & 1);
        EXPECT_EQ(kCornerOffset[c][2], (c >> 2) & 1);
    }
    const float samples[8] = {0.f, 2.f, 1.f, 3.f, 1.f, 0.5f, 2.f, -1.f};
    EXPECT_EQ(mcCaseIndex(samples, 1.0), 0b01001010);  // s > iso, so s == iso is below
}

TEST(McTables, EveryCrossedEdgeUsedExactlyOnce) {
    for (int caseIndex = 0; caseIndex < kMcCaseCount; ++caseIndex) {
        uint16_t crossed = 0;
        for (int e = 0; e < kMcEdgeCount; ++e) {
            if (isAboveIn(caseIndex, kEdgeCorners[e][0]) !=
                isAboveIn(caseIndex, kEdgeCorners[e][1]))
                crossed |= uint16_t(1u << e);
        }
        ASSERT_EQ(mcCrossedEdges(caseIndex), crossed) << "case " << caseIndex;

        const McPolygonCase& pc = mcPolygonCase(caseIndex);
        ASSERT_LE(pc.polygonCount, kMcMaxPolygons);
        int uses[kMcEdgeCount] = {};
        int vertexTotal = 0;
        for (int p = 0; p < kMcMaxPolygons; ++p) {
            if (p < pc.polygonCount) {
                EXPECT_GE(pc.vertexCount[p], 3) << "case " << caseIndex;
                EXPECT_LE(pc.vertexCount[p], kMcMaxPolygonVertices) << "case " << caseIndex;
            } else {
                EXPECT_EQ(pc.vertexCount[p], 0) << "case " << caseIndex;
            }
            vertexTotal += pc.vertexCount[p];
        }
        ASSERT_LE(vertexTotal, kMcEdgeCount);
        for (int i = 0; i < vertexTotal; ++i) {
            ASSERT_LT(pc.edges[i], kMcEdgeCount);
            ++uses[pc.edges[i]];
        }
        for (int e = 0; e < kMcEdgeCount; ++e)
            EXPECT_EQ(uses[e], (crossed >> e) & 1) << "case " << caseIndex << " edge " << e;
    }
}

TEST(McTables, PolygonsAreClosedLoopsAlongFaces) {
    for (int caseIndex = 0; caseIndex < kMcCaseCount; ++caseIndex) {
        for (const std::vector<int>& poly : polygonsOf(caseIndex)) {
            for (size_t i = 0; i < poly.size(); ++i) {
                const int a = poly[i], b = poly[(i + 1) % poly.size()];  // last -> first too
                EXPECT_NE(commonFace(a, b), -1)
                    << "case " << caseIndex << ": edges " << a << " and " << b << " share no face";
            }
        }
    }
}

// The bounds in the header are exactly what the tables need, no more.
TEST(McTables, BoundsAreTight) {
    int maxPolygons = 0, maxVertices = 0, maxTriangles = 0, triangleTotal = 0, polygonTotal = 0;
    for (int caseIndex = 0; caseIndex < kMcCaseCount; ++caseIndex) {
        const McPolygonCase& pc = mcPolygonCase(caseIndex);
        maxPolygons = std::max(maxPolygons, int(pc.polygonCount));
        for (int p = 0; p < pc.polygonCount; ++p)
            maxVertices = std::max(maxVertices, int(pc.vertexCount[p]));
        maxTriangles = std::max(maxTriangles, int(mcTriangleCase(caseIndex).triangleCount));
        triangleTotal += mcTriangleCase(caseIndex).triangleCount;
        polygonTotal += pc.polygonCount;
    }
    EXPECT_EQ(maxPolygons, kMcMaxPolygons);
    EXPECT_EQ(maxVertices, kMcMaxPolygonVertices);
    EXPECT_EQ(maxTriangles, kMcMaxTriangles);
    // Pinned so a change to the generator shows up: 358 polygons (144 triangles, 66 quads,
    // 72 pentagons, 52 hexagons, 24 heptagons) fanned into 820 triangles.
    EXPECT_EQ(polygonTotal, 358);
    EXPECT_EQ(triangleTotal, 820);
}

TEST(McTables, TrianglesAreFansOfPolygons) {
    for (int caseIndex = 0; caseIndex < kMcCaseCount; ++caseIndex) {
        std::vector<int> fan;
        for (const std::vector<int>& poly : polygonsOf(caseIndex)) {
            for (size_t i = 1; i + 1 < poly.size(); ++i)
                fan.insert(fan.end(), {poly[0], poly[i], poly[i + 1]});
        }
        const McTriangleCase& tc = mcTriangleCase(caseIndex);
        ASSERT_EQ(size_t(3 * tc.triangleCount), fan.size()) << "case " << caseIndex;
        EXPECT_TRUE(std::equal(fan.begin(), fan.end(), tc.edges)) << "case " << caseIndex;
    }
}

// No fan diagonal lies in a cube face: it could coincide with one the neighbouring cell emits.
TEST(McTables, FanDiagonalsLeaveTheFaces) {
    for (int caseIndex = 0; caseIndex < kMcCaseCount; ++caseIndex) {
        for (const std::vector<int>& poly : polygonsOf(caseIndex)) {
            for (size_t i = 2; i + 1 < poly.size(); ++i)
                EXPECT_EQ(commonFace(poly[0], poly[i]), -1) << "case " << caseIndex;
        }
    }
}

// Each fan triangle crosses every edge it has a vertex on from the above corner to the below
// one, or runs parallel to it; never back (which would fold the surface around that edge).
TEST(McTables, FanTrianglesDoNotFoldAroundEdges) {
    for (int caseIndex = 0; caseIndex < kMcCaseCount; ++caseIndex) {
        const McTriangleCase& tc = mcTriangleCase(caseIndex);
        for (int t = 0; t < tc.triangleCount; ++t) {
            const uint8_t* v = tc.edges + 3 * t;
            const Vec3 p0 = edgeMidpoint(v[0]);
            const Vec3 normal = cross(edgeMidpoint(v[1]) - p0, edgeMidpoint(v[2]) - p0);
            EXPECT_GT(length(normal), 1e-9) << "case " << caseIndex << " triangle " << t;
            for (int k = 0; k < 3; ++k) {
                const int a = kEdgeCorners[v[k]][0], b = kEdgeCorners[v[k]][1];
                const Vec3 aboveToBelow = isAboveIn(caseIndex, a)
                                              ? cornerPosition(b) - cornerPosition(a)
                                              : cornerPosition(a) - cornerPosition(b);
                EXPECT_GE(dot(normal, aboveToBelow), 0.0)
                    << "case " << caseIndex << " triangle " << t << " edge " << int(v[k]);
            }
        }
    }
}

// The segments on a face depend only on that face's corners, and the cell on the other side
// of the face walks them the other way: no cracks, consistent orientation.
TEST(McTables, FaceSegmentsAgreeAcrossSharedFaces) {
    for (int axis = 0; axis < 3; ++axis) {
        const int highFace = 2 * axis + 1, lowFace = 2 * axis;  // lower cell's, upper cell's
        for (int pattern = 0; pattern < 16; ++pattern) {
            // The face's corners carry the pattern, bit k on its k-th corner in corner order
            // (the same physical corner from either cell); the other four carry `others`.
            auto caseWith = [&](int face, int others) {
                int caseIndex = 0, onFace = 0, off = 0;
                for (int c = 0; c < 8; ++c) {
                    const int bit =
                        cornerOnFace(c, face) ? (pattern >> onFace++) & 1 : (others >> off++) & 1;
                    caseIndex |= bit << c;
                }
                return caseIndex;
            };
            // Edge e on the upper cell's low face is, in the lower cell, the edge whose corners
            // are e's corners moved one step along axis.
            auto toLowerCell = [&](int e) {
                const int a = kEdgeCorners[e][0] | (1 << axis),
                          b = kEdgeCorners[e][1] | (1 << axis);
                for (int f = 0; f < kMcEdgeCount; ++f) {
                    if (kEdgeCorners[f][0] == a && kEdgeCorners[f][1] == b) return f;
                }
                return -1;
            };
            const std::set<std::pair<int, int>> reference =
                faceSegments(caseWith(highFace, 0), highFace);
            for (int others = 0; others < 16; ++others) {
                EXPECT_EQ(faceSegments(caseWith(highFace, others), highFace), reference)
                    << "axis " << axis << " pattern " << pattern;
                std::set<std::pair<int, int>> upper;
                for (auto [a, b] : faceSegments(caseWith(lowFace, others), lowFace))
                    upper.insert({toLowerCell(b), toLowerCell(a)});  // reversed
                EXPECT_EQ(upper, reference) << "axis " << axis << " pattern " << pattern;
            }
        }
    }
}

// Ambiguous faces: each segment cuts off a single above corner, so the two above corners are
// separated and the below ones connect.
TEST(McTables, AmbiguousFacesSeparateAboveCorners) {
    int ambiguousSeen = 0;
    for (int caseIndex = 0; caseIndex < kMcCaseCount; ++caseIndex) {
        for (int face = 0; face < 6; ++face) {
            std::vector<int> above, below;
            for (int c = 0; c < 8; ++c) {
                if (cornerOnFace(c, face)) (isAboveIn(caseIndex, c) ? above : below).push_back(c);
            }
            if (above.size() != 2 || ((above[0] ^ above[1]) & ((above[0] ^ above[1]) - 1)) == 0)
                continue;  // not two diagonal corners above (their xor has two bits set)
            ++ambiguousSeen;
            const std::set<std::pair<int, int>> segments = faceSegments(caseIndex, face);
            ASSERT_EQ(segments.size(), 2u) << "case " << caseIndex << " face " << face;
            for (auto [a, b] : segments) {
                auto aboveCorner = [&](int e) {
                    return isAboveIn(caseIndex, kEdgeCorners[e][0]) ? kEdgeCorners[e][0]
                                                                    : kEdgeCorners[e][1];
                };
                EXPECT_EQ(aboveCorner(a), aboveCorner(b)) << "case " << caseIndex;
            }
        }
    }
    EXPECT_EQ(ambiguousSeen, 6 * 2 * 16);  // per face: 2 diagonals times 16 other-corner cases
}

// With vertices at the edge midpoints, each polygon's Newell normal points from the above
// corners it cuts off towards the below ones, and every fan triangle faces the same way.
TEST(McTables, PolygonsFaceTheBelowSide) {
    for (int caseIndex = 0; caseIndex < kMcCaseCount; ++caseIndex) {
        for (const std::vector<int>& poly : polygonsOf(caseIndex)) {
            std::vector<Vec3> loop;
            Vec3 aboveSum, belowSum;
            for (int e : poly) {
                loop.push_back(edgeMidpoint(e));
                const int a = kEdgeCorners[e][0], b = kEdgeCorners[e][1];
                const bool aAbove = isAboveIn(caseIndex, a);
                aboveSum = aboveSum + cornerPosition(aAbove ? a : b);
                belowSum = belowSum + cornerPosition(aAbove ? b : a);
            }
            const Vec3 normal = newellNormal(loop);
            // Sum over the polygon's edges of (below corner - above corner): a gradient estimate.
            EXPECT_GT(dot(normal, belowSum - aboveSum), 0.0) << "case " << caseIndex;
            for (size_t i = 1; i + 1 < loop.size(); ++i) {
                const Vec3 t = cross(loop[i] - loop[0], loop[i + 1] - loop[0]);
                EXPECT_GT(dot(t, normal), 1e-9) << "case " << caseIndex << " fan triangle " << i;
            }
        }
        // Single corner cases, by hand: the normal points away from the lone corner.
        for (int c = 0; c < 8 && std::popcount(unsigned(caseIndex)) == 1; ++c) {
            if (caseIndex != 1 << c) continue;
            const McTriangleCase& tc = mcTriangleCase(caseIndex);
            ASSERT_EQ(tc.triangleCount, 1);
            const Vec3 p0 = edgeMidpoint(tc.edges[0]), p1 = edgeMidpoint(tc.edges[1]),
                       p2 = edgeMidpoint(tc.edges[2]);
            const Vec3 awayFromCorner = Vec3{0.5, 0.5, 0.5} - cornerPosition(c);
            EXPECT_GT(dot(cross(p1 - p0, p2 - p0), awayFromCorner), 0.0) << "corner " << c;
        }
    }
}

// Counts how often the segment from p to q crosses a triangle (Moller-Trumbore).
int crossings(Vec3 p, Vec3 q, const std::vector<std::array<Vec3, 3>>& triangles) {
    int count = 0;
    const Vec3 d = q - p;
    for (const std::array<Vec3, 3>& t : triangles) {
        const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
        const Vec3 h = cross(d, e2);
        const double det = dot(e1, h);
        if (std::abs(det) < 1e-14) continue;
        const Vec3 s = p - t[0];
        const double u = dot(s, h) / det;
        const Vec3 qq = cross(s, e1);
        const double v = dot(d, qq) / det;
        const double along = dot(e2, qq) / det;
        if (u >= 0 && v >= 0 && u + v <= 1 && along >= 0 && along <= 1) ++count;
    }
    return count;
}

// The surface in the cell separates the corners as their signs say: paths just inside the
// cube between two corners cross it an odd number of times exactly when their signs differ;
// along a cube edge exactly once or never; across an ambiguous face twice between the above
// corners (separated) and never between the below ones (connected).
TEST(McTables, SurfaceSeparatesCornersBySign) {
    const double inset = 1e-3;
    // A point near corner c, just inside the cube, nudged off any symmetric plane.
    auto nearCorner = [&](int c, double jitter) {
        const Vec3 p = cornerPosition(c);
        return p + inset * (Vec3{0.5, 0.5, 0.5} - p) +
               Vec3{jitter * 1.3e-4, jitter * 0.7e-4, jitter * 1.1e-4};
    };
    for (int caseIndex = 0; caseIndex < kMcCaseCount; ++caseIndex) {
        const McTriangleCase& tc = mcTriangleCase(caseIndex);
        std::vector<std::array<Vec3, 3>> triangles;
        for (int t = 0; t < tc.triangleCount; ++t) {
            triangles.push_back({edgeMidpoint(tc.edges[3 * t]), edgeMidpoint(tc.edges[3 * t + 1]),
                                 edgeMidpoint(tc.edges[3 * t + 2])});
        }
        for (int a = 0; a < 8; ++a) {
            for (int b = a + 1; b < 8; ++b) {
                for (double jitter : {1.0, -0.6, 0.3}) {
                    const int n =
                        crossings(nearCorner(a, jitter), nearCorner(b, -0.7 * jitter), triangles);
                    const bool differ = isAboveIn(caseIndex, a) != isAboveIn(caseIndex, b);
                    EXPECT_EQ(n % 2, int(differ)) << "case " << caseIndex << " corners " << a << b;
                    const int hamming = std::popcount(unsigned(a ^ b));
                    if (hamming == 1) {
                        EXPECT_EQ(n, int(differ)) << "case " << caseIndex << " edge " << a << b;
                    } else if (hamming == 2 && !differ) {
                        // Both corners on one face: path runs just inside that face.
                        const int common = ~(a ^ b) & 7;
                        const int axis = common == 1 ? 0 : common == 2 ? 1 : 2;
                        int face = 2 * axis + ((a >> axis) & 1);
                        bool ambiguous = true;
                        for (int c = 0; c < 8; ++c) {
                            if (cornerOnFace(c, face) && c != a && c != b)
                                ambiguous =
                                    ambiguous && isAboveIn(caseIndex, c) != isAboveIn(caseIndex, a);
                        }
                        const int expected = ambiguous && isAboveIn(caseIndex, a) ? 2 : 0;
                        EXPECT_EQ(n, expected)
                            << "case " << caseIndex << " face diagonal " << a << b;
                    }
                }
            }
        }
    }
}

// ---- Whole volumes: a reference extractor that welds vertices by global edge id. ----

struct Grid {
    int nx, ny, nz;
    std::vector<float> samples;

    float at(int x, int y, int z) const { return samples[(size_t(z) * ny + y) * nx + x]; }
    float& at(int x, int y, int z) { return samples[(size_t(z) * ny + y) * nx + x]; }
};

struct Surface {
    std::vector<std::vector<uint64_t>> faces;  // loops of global edge keys
    std::map<uint64_t, Vec3> positions;
};

// Triangles (or polygons, usePolygons) of the isosurface, vertices linearly interpolated.
Surface extract(const Grid& g, double iso, bool usePolygons) {
    Surface s;
    for (int z = 0; z + 1 < g.nz; ++z) {
        for (int y = 0; y + 1 < g.ny; ++y) {
            for (int x = 0; x + 1 < g.nx; ++x) {
                float corner[8];
                for (int c = 0; c < 8; ++c)
                    corner[c] = g.at(x + kCornerOffset[c][0], y + kCornerOffset[c][1],
                                     z + kCornerOffset[c][2]);
                const int caseIndex = mcCaseIndex(corner, iso);
                auto vertex = [&](int e) {
                    const int a = kEdgeCorners[e][0], b = kEdgeCorners[e][1];
                    const uint64_t gx = x + kCornerOffset[a][0], gy = y + kCornerOffset[a][1],
                                   gz = z + kCornerOffset[a][2];
                    const uint64_t key = ((gz * g.ny + gy) * g.nx + gx) * 3 + mcEdgeAxis(e);
                    const double t = (iso - corner[a]) / (double(corner[b]) - corner[a]);
                    const Vec3 origin{double(x), double(y), double(z)};
                    s.positions[key] =
                        origin + cornerPosition(a) + t * (cornerPosition(b) - cornerPosition(a));
                    return key;
                };
                if (usePolygons) {
                    for (const std::vector<int>& poly : polygonsOf(caseIndex)) {
                        std::vector<uint64_t> face;
                        for (int e : poly) face.push_back(vertex(e));
                        s.faces.push_back(face);
                    }
                } else {
                    const McTriangleCase& tc = mcTriangleCase(caseIndex);
                    for (int t = 0; t < tc.triangleCount; ++t) {
                        s.faces.push_back({vertex(tc.edges[3 * t]), vertex(tc.edges[3 * t + 1]),
                                           vertex(tc.edges[3 * t + 2])});
                    }
                }
            }
        }
    }
    return s;
}

// Closed and consistently oriented: every undirected edge is used by exactly two faces, once
// in each direction. Returns the Euler characteristic V - E + F (or a huge value on failure).
int64_t checkClosedOriented(const Surface& s) {
    std::map<std::pair<uint64_t, uint64_t>, int> directed;
    for (const std::vector<uint64_t>& f : s.faces) {
        for (size_t i = 0; i < f.size(); ++i) ++directed[{f[i], f[(i + 1) % f.size()]}];
    }
    int failures = 0;
    for (const auto& [edge, count] : directed) {
        auto reverse = directed.find({edge.second, edge.first});
        const int back = reverse == directed.end() ? 0 : reverse->second;
        if (count != 1 || back != 1) ++failures;
    }
    EXPECT_EQ(failures, 0) << "edges not shared by exactly two faces in opposite directions";
    if (failures) return INT64_MAX;
    return int64_t(s.positions.size()) - int64_t(directed.size() / 2) + int64_t(s.faces.size());
}

// Fan-triangulates polygon faces for the sums below (triangles pass through unchanged).
template <class Visit>
void forEachTriangle(const Surface& s, Visit&& visit) {
    for (const std::vector<uint64_t>& f : s.faces) {
        for (size_t i = 1; i + 1 < f.size(); ++i)
            visit(s.positions.at(f[0]), s.positions.at(f[i]), s.positions.at(f[i + 1]));
    }
}

// Volume enclosed, by the divergence theorem: positive when normals point outward.
double enclosedVolume(const Surface& s) {
    double volume = 0;
    forEachTriangle(s, [&](Vec3 a, Vec3 b, Vec3 c) { volume += dot(a, cross(b, c)) / 6; });
    return volume;
}

double area(const Surface& s) {
    double sum = 0;
    forEachTriangle(s, [&](Vec3 a, Vec3 b, Vec3 c) { sum += 0.5 * length(cross(b - a, c - a)); });
    return sum;
}

Grid randomGrid(int nx, int ny, int nz, uint32_t seed, bool binary) {
    Grid g{nx, ny, nz, std::vector<float>(size_t(nx) * ny * nz, 0.f)};
    std::mt19937 rng(seed);
    for (int z = 1; z + 1 < nz; ++z) {
        for (int y = 1; y + 1 < ny; ++y) {
            for (int x = 1; x + 1 < nx; ++x) {
                const float u = float(rng() >> 8) * (1.f / 16777216.f);  // [0, 1)
                g.at(x, y, z) = binary ? float(u < 0.5f) : u;
            }
        }
    }
    return g;  // the border stays 0, below every isovalue used: the surface closes
}

TEST(McTables, RandomVolumeSurfaceIsClosedAndOriented) {
    for (uint32_t seed : {1u, 2u, 3u}) {
        const Grid g = randomGrid(12, 11, 10, seed, /*binary=*/false);
        for (double iso : {0.25, 0.5, 0.75}) {
            SCOPED_TRACE("seed " + std::to_string(seed) + " iso " + std::to_string(iso));
            const Surface triangles = extract(g, iso, /*usePolygons=*/false);
            const Surface polygons = extract(g, iso, /*usePolygons=*/true);
            ASSERT_GT(triangles.faces.size(), 100u);
            checkClosedOriented(triangles);
            checkClosedOriented(polygons);
            // Outward normals (above inside, border below) enclose a positive volume; both
            // forms describe the same surface.
            EXPECT_GT(enclosedVolume(triangles), 0.0);
            EXPECT_NEAR(enclosedVolume(polygons), enclosedVolume(triangles), 1e-9);
            EXPECT_NEAR(area(polygons), area(triangles), 1e-9);
        }
    }
}

// Only 0 and 1 samples: every ambiguous face configuration shows up many times.
TEST(McTables, BinaryVolumeSurfaceIsClosedAndOriented) {
    for (uint32_t seed = 10; seed < 20; ++seed) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        const Grid g = randomGrid(12, 11, 10, seed, /*binary=*/true);
        const Surface triangles = extract(g, 0.5, false);
        checkClosedOriented(triangles);
        checkClosedOriented(extract(g, 0.5, true));
        EXPECT_GT(enclosedVolume(triangles), 0.0);
    }
}

TEST(McTables, SphereIsClosedGenusZero) {
    const int n = 24;
    const Vec3 center{11.3, 11.7, 12.1};
    const double radius = 8.2;
    Grid g{n, n, n, std::vector<float>(size_t(n) * n * n)};
    for (int z = 0; z < n; ++z) {
        for (int y = 0; y < n; ++y) {
            for (int x = 0; x < n; ++x)
                g.at(x, y, z) =
                    float(radius - length(Vec3{double(x), double(y), double(z)} - center));
        }
    }
    const Surface triangles = extract(g, 0.0, false);
    const Surface polygons = extract(g, 0.0, true);
    EXPECT_EQ(checkClosedOriented(triangles), 2);
    EXPECT_EQ(checkClosedOriented(polygons), 2);  // polygons are disks: still a sphere
    const double pi = 3.14159265358979323846;
    EXPECT_NEAR(enclosedVolume(triangles) / (4.0 / 3.0 * pi * radius * radius * radius), 1.0, 0.02);
    EXPECT_NEAR(area(triangles) / (4.0 * pi * radius * radius), 1.0, 0.03);
    // Every triangle faces away from the centre (minus the gradient of the distance field).
    int inward = 0;
    forEachTriangle(triangles, [&](Vec3 a, Vec3 b, Vec3 c) {
        inward += dot(cross(b - a, c - a), (1.0 / 3.0) * (a + b + c) - center) <= 0;
    });
    EXPECT_EQ(inward, 0);
}

// A 6x6x6 block of samples 1 in a volume of 0, iso 0.5: the surface is the box [1.5, 7.5]^3
// (the block spans samples 2..7) with its edges and corners bevelled, all exactly known.
//  - Face cells (four above corners forming a cell face): a unit square at the midplane;
//    5 x 5 per box face, 2 triangles each: 6 * 25 * 2 = 300 triangles, area 150.
//  - Edge cells (two above corners, a cell edge): a 1 x sqrt(1/2) rectangle at 45 degrees;
//    5 per box edge, 2 triangles each: 12 * 5 * 2 = 120 triangles, area 60 sqrt(1/2).
//  - Corner cells (one above corner): a triangle with legs 1/2 along the cell edges; 8
//    triangles of area (sqrt(3) / 4) * (1/2), so sqrt(3) in all.
//  - Volume: the box 6^3, less per edge cell the prism 1/2 (1/4 - 1/8) = 1/8 and per corner
//    cell the cube 1/8 less the tetrahedron (1/2)^3 / 6 = 1/48, i.e. 5/48.
TEST(McTables, BevelledBoxIsExact) {
    const int n = 10;
    Grid g{n, n, n, std::vector<float>(size_t(n) * n * n, 0.f)};
    for (int z = 2; z <= 7; ++z) {
        for (int y = 2; y <= 7; ++y) {
            for (int x = 2; x <= 7; ++x) g.at(x, y, z) = 1.f;
        }
    }
    const Surface triangles = extract(g, 0.5, false);
    EXPECT_EQ(triangles.faces.size(), 300u + 120u + 8u);
    EXPECT_EQ(checkClosedOriented(triangles), 2);
    const double expectedArea = 150 + 60 * std::sqrt(0.5) + std::sqrt(3.0);
    const double expectedVolume = 216 - 60 * (1.0 / 8) - 8 * (5.0 / 48);
    EXPECT_NEAR(area(triangles) / expectedArea, 1.0, 1e-6);
    EXPECT_NEAR(enclosedVolume(triangles) / expectedVolume, 1.0, 1e-6);

    const Surface polygons = extract(g, 0.5, true);
    EXPECT_EQ(polygons.faces.size(), 150u + 60u + 8u);  // one polygon per cell
    EXPECT_EQ(checkClosedOriented(polygons), 2);
}

}  // namespace
}  // namespace vdiso
