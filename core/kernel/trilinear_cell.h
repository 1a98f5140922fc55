// A cell's surface with the topology of its trilinear interpolant: what Lewiner et al. ("Efficient
// implementation of Marching Cubes' cases with topological guarantees", 2003, after Chernyaev's
// MC33) guarantee, and scikit-image's default method="lewiner" gives. The tables
// (core/kernel/mc_tables.h) cut every ambiguous face one way and never join two pieces inside a
// cell; here, from the cell's eight samples:
//  - each ambiguous face is cut as its bilinear interpolant is (the asymptotic decider: the
//    above diagonal is joined when the product of its values exceeds the below diagonal's,
//    values taken about the isovalue), so the two cells sharing the face agree;
//  - the pieces of one side (above or below) that the faces leave apart but the trilinear
//    interpolant joins inside the cell (a tunnel) are found by sweeping planes z = t through the
//    cell: each plane's bilinear interpolant has its pieces joined as its corners' signs and its
//    own decider say, and these change only where a vertical edge is crossed or the plane's
//    decider changes sign (the roots of one linear and one quadratic function of t), so one
//    plane between each two such t decides the whole slab;
//  - the two loops such a tunnel joins become one tube, zipped between them; every other loop
//    is a disc.
// The loops are mc_tables' loops (mcPolygonsJoined), in its orientation. Discs and tubes are
// triangulated so that no chord lies in one of the cell's lower faces, where the neighbour's
// triangles could meet it (a cell's chords in its upper faces are allowed, dearer); when that
// cannot be done a vertex inside the cell takes the chords (a disc's fan from it; a tube's
// walk passing it), as Lewiner's tables add one in some cases.
#pragma once

#include <cstdint>

namespace vdiso {

// At most: 12 crossed edges in loops, a loop's disc as many triangles as edges (from a vertex
// inside), a tube's m + n and two more for each vertex inside it.
constexpr int kTrilinearMaxTriangles = 24;
// Vertices inside the cell a cut may add (one a disc that needs one, one a run of a tube's walk
// that needs one) and their ids.
constexpr int kTrilinearMaxCentres = 6;
constexpr int kTrilinearCentre = 12;  // the first one's id among the triangles' edge ids

struct TrilinearCell {
    int triangleCount = 0;
    // Three ids a triangle: an edge id (its crossing, as McTriangleCase), or kTrilinearCentre + k
    // for centre k.
    uint8_t edges[3 * kTrilinearMaxTriangles];
    int centreCount = 0;
    double centres[kTrilinearMaxCentres][3];  // in the cell's unit cube
    // A tunnel joined other than two loops (never seen: tests); the loops were fanned apart.
    bool unresolved = false;
};

// Whether trilinearCell can cut case `caseIndex` otherwise than mcPolygonCase: it has an
// ambiguous face, or one side in two or more pieces on the cell's faces (a tunnel may join them).
bool trilinearMayDiffer(int caseIndex);

// The triangles of the cell whose corner k (core/kernel/mc_tables.h numbering) has value f[k]
// minus the isovalue; above is f > 0, as the case index has it.
void trilinearCell(const double f[8], TrilinearCell& out);

// The gradient of the interpolant of corner values f at point p of the cell's unit cube (per
// unit of the cube: divide by the spacing for the world's).
void trilinearGradient(const double f[8], const double p[3], double gradient[3]);

}  // namespace vdiso
