#include "core/kernel/trilinear_cell.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>

#include "core/kernel/mc_tables.h"

namespace vdiso {
namespace {

// Union-find over a few nodes.
template <int N>
struct Groups {
    int parent[N];
    Groups() {
        for (int i = 0; i < N; ++i) parent[i] = i;
    }
    int find(int i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    }
    void join(int a, int b) { parent[find(a)] = find(b); }
};

bool onSide(double v, bool above) { return above ? v > 0 : !(v > 0); }

// Of two diagonal pairs (values a, c and b, d) with a, c on `side` and b, d not: whether the
// bilinear interpolant joins a and c. Above is joined when a c > b d (the asymptotic decider),
// below when it is not, so that exactly one diagonal is joined, on a face and in a plane alike.
bool diagonalJoined(double a, double c, double b, double d, bool above) {
    const double inside = a * c, outside = b * d;
    return above ? inside - outside > 0 : !(outside - inside > 0);
}

// The faces cut the other way (mcPolygonsJoined): the ambiguous faces whose above diagonal the
// face's bilinear interpolant joins.
int joinedFaces(const double f[8], int caseIndex) {
    const int ambiguous = mcAmbiguousFaces(caseIndex);
    int mask = 0;
    for (int face = 0; face < 6; ++face) {
        if (!((ambiguous >> face) & 1)) continue;
        const std::array<int, 4>& q = mcFaceCorners()[size_t(face)];
        const bool firstAbove = f[q[0]] > 0;
        const double a = firstAbove ? f[q[0]] : f[q[1]], c = firstAbove ? f[q[2]] : f[q[3]];
        const double b = firstAbove ? f[q[1]] : f[q[0]], d = firstAbove ? f[q[3]] : f[q[2]];
        if (diagonalJoined(a, c, b, d, true)) mask |= 1 << face;
    }
    return mask;
}

// The corners on `side` grouped as the cell's faces join them: along edges, and across the
// ambiguous faces cut to join that side.
Groups<8> faceGroups(const double f[8], int caseIndex, int joinAbove, bool above) {
    Groups<8> g;
    for (int e = 0; e < kMcEdgeCount; ++e) {
        const int a = kEdgeCorners[e][0], b = kEdgeCorners[e][1];
        if (onSide(f[a], above) && onSide(f[b], above)) g.join(a, b);
    }
    const int ambiguous = mcAmbiguousFaces(caseIndex);
    for (int face = 0; face < 6; ++face) {
        if (!((ambiguous >> face) & 1) || bool((joinAbove >> face) & 1) != above) continue;
        const std::array<int, 4>& q = mcFaceCorners()[size_t(face)];
        const int k = onSide(f[q[0]], above) ? 0 : 1;
        g.join(q[size_t(k)], q[size_t(k + 2)]);
    }
    return g;
}

// The corners on `side` grouped as the trilinear interpolant joins them inside the cell, by
// the sweep of planes z = t (trilinear_cell.h). Plane corner j is the vertical edge at
// (x, y) = (0,0), (1,0), (1,1), (0,1): cyclic, so j and j + 2 are diagonal.
Groups<8> interiorGroups(const double f[8], bool above) {
    constexpr int kBottom[4] = {0, 1, 3, 2};
    double b[4], d[4];
    for (int j = 0; j < 4; ++j) {
        b[j] = f[kBottom[j]];
        d[j] = f[kBottom[j] + 4] - b[j];
    }
    // Where the planes' pieces can change: a vertical edge crossed, the planes' decider zero.
    double cuts[8] = {0.0};
    int n = 1;
    auto add = [&](double t) {
        if (t > 0 && t < 1) cuts[n++] = t;
    };
    for (int j = 0; j < 4; ++j)
        if ((b[j] > 0) != (b[j] + d[j] > 0)) add(b[j] / -d[j]);
    const double qa = d[0] * d[2] - d[1] * d[3];
    const double qb = b[0] * d[2] + d[0] * b[2] - b[1] * d[3] - d[1] * b[3];
    const double qc = b[0] * b[2] - b[1] * b[3];
    if (qa == 0) {
        if (qb != 0) add(-qc / qb);
    } else {
        const double disc = qb * qb - 4 * qa * qc;
        if (disc >= 0) {
            const double r = std::sqrt(disc);
            add((-qb - r) / (2 * qa));
            add((-qb + r) / (2 * qa));
        }
    }
    cuts[n++] = 1.0;
    std::sort(cuts, cuts + n);
    // Node s * 4 + j: plane corner j in slab s (between cuts s and s + 1).
    Groups<32> g;
    bool in[8][4] = {};
    const int slabs = n - 1;
    for (int s = 0; s < slabs; ++s) {
        const double t = 0.5 * (cuts[s] + cuts[s + 1]);
        double a[4];
        for (int j = 0; j < 4; ++j) {
            a[j] = b[j] + d[j] * t;
            in[s][j] = onSide(a[j], above);
        }
        for (int j = 0; j < 4; ++j) {
            if (in[s][j] && in[s][(j + 1) % 4]) g.join(s * 4 + j, s * 4 + (j + 1) % 4);
            if (s > 0 && in[s][j] && in[s - 1][j]) g.join(s * 4 + j, (s - 1) * 4 + j);
        }
        if (in[s][0] == in[s][2] && in[s][1] == in[s][3] && in[s][0] != in[s][1]) {
            const int k = in[s][0] ? 0 : 1;
            if (diagonalJoined(a[k], a[k + 2], a[1 - k], a[3 - k], above)) g.join(s * 4 + k, s * 4 + k + 2);
        }
    }
    // Each corner on the side belongs to its edge's node in the first (bottom) or last slab.
    Groups<8> corners;
    int node[8];
    for (int j = 0; j < 4; ++j) {
        node[kBottom[j]] = in[0][j] ? g.find(j) : -1 - kBottom[j];
        node[kBottom[j] + 4] = in[slabs - 1][j] ? g.find((slabs - 1) * 4 + j) : -5 - kBottom[j];
    }
    for (int c = 0; c < 8; ++c)
        for (int e = c + 1; e < 8; ++e)
            if (onSide(f[c], above) && onSide(f[e], above) && node[c] == node[e]) corners.join(c, e);
    return corners;
}

// Where edge e is crossed, in the cell's unit cube.
std::array<double, 3> crossing(const double f[8], int e) {
    const int a = kEdgeCorners[e][0], b = kEdgeCorners[e][1];
    const double t = std::clamp(f[a] / (f[a] - f[b]), 0.0, 1.0);
    std::array<double, 3> p;
    for (int k = 0; k < 3; ++k) p[size_t(k)] = kCornerOffset[a][k] + t * (kCornerOffset[b][k] - kCornerOffset[a][k]);
    return p;
}

double distance2(const std::array<double, 3>& p, const std::array<double, 3>& q) {
    return (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
}

void addTriangle(TrilinearCell& out, int a, int b, int c) {
    uint8_t* w = out.edges + 3 * out.triangleCount++;
    w[0] = uint8_t(a);
    w[1] = uint8_t(b);
    w[2] = uint8_t(c);
}

constexpr double kNoWay = 1e300;

// A chord between the crossings of edges e and f, p and q: its length; more when it lies in
// one of the cell's upper faces (x, y or z = 1), kNoWay in a lower one. A chord in a face is
// where two triangles of this cell meet on that face; were the neighbour across it to put a
// chord there too, four triangles would meet at it. So only the cell below a face may:
// the one whose upper face it is.
double chordCost(int e, int f, const std::array<double, 3>& p, const std::array<double, 3>& q) {
    const double length = std::sqrt(distance2(p, q));
    if (!mcEdgesShareFace(e, f)) return length;
    const int corners[4] = {kEdgeCorners[e][0], kEdgeCorners[e][1], kEdgeCorners[f][0], kEdgeCorners[f][1]};
    bool lower = false;
    for (int axis = 0; axis < 3; ++axis) {
        bool onLower = true;
        for (const int c : corners) onLower = onLower && !((c >> axis) & 1);
        lower = lower || onLower;
    }
    return lower ? kNoWay : length + 4.0;
}

double chord(const std::array<double, 3>* p, const uint8_t* e, int a, int b) { return chordCost(e[a], e[b], p[a], p[b]); }

// A vertex inside the cell: the mean of the crossings given; its id in out.edges.
int addCentre(TrilinearCell& out, const std::array<double, 3>* p, int n, const std::array<double, 3>* q = nullptr,
              int nq = 0) {
    std::array<double, 3> c{0.0, 0.0, 0.0};
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) c[size_t(k)] += p[i][size_t(k)];
    for (int i = 0; i < nq; ++i)
        for (int k = 0; k < 3; ++k) c[size_t(k)] += q[i][size_t(k)];
    for (int k = 0; k < 3; ++k) out.centres[out.centreCount][k] = c[size_t(k)] / double(n + nq);
    return kTrilinearCentre + out.centreCount++;
}

// The disc of loop v (n edges, mc_tables' orientation): the triangulation whose chords lie in
// no lower face and cost least (chordCost); when every one needs such a chord, the fan from a
// vertex inside the cell.
void disc(const double f[8], const uint8_t* v, int n, TrilinearCell& out) {
    std::array<double, 3> p[kMcEdgeCount];
    for (int i = 0; i < n; ++i) p[i] = crossing(f, v[i]);
    // cost[i][j]: the chain i..j closed by chord (i, j) triangulated; split[i][j] its apex.
    double cost[kMcEdgeCount][kMcEdgeCount];
    int split[kMcEdgeCount][kMcEdgeCount];
    for (int gap = 1; gap < n; ++gap)
        for (int i = 0; i + gap < n; ++i) {
            const int j = i + gap;
            cost[i][j] = 0;
            split[i][j] = -1;
            if (gap == 1) continue;
            const double closing = gap == n - 1 ? 0.0 : chord(p, v, i, j);
            double best = kNoWay;
            for (int k = i + 1; k < j; ++k) {
                const double c = cost[i][k] + cost[k][j];
                if (c < best) best = c, split[i][j] = k;
            }
            cost[i][j] = closing >= kNoWay || best >= kNoWay ? kNoWay : best + closing;
        }
    if (n > 3 && cost[0][n - 1] >= kNoWay) {
        const int c = addCentre(out, p, n);
        for (int k = 0; k < n; ++k) addTriangle(out, c, v[k], v[(k + 1) % n]);
        return;
    }
    // The triangles, from the whole chain down (a stack of chains).
    int stack[2 * kMcEdgeCount], top = 0;
    stack[top++] = 0;
    stack[top++] = n - 1;
    while (top) {
        const int j = stack[--top], i = stack[--top];
        if (j - i < 2) continue;
        const int k = split[i][j];
        addTriangle(out, v[i], v[k], v[j]);
        stack[top++] = i, stack[top++] = k;
        stack[top++] = k, stack[top++] = j;
    }
}

// The tube between loops a (m edges) and b (n edges), each in mc_tables' orientation (the
// surface on its left): from a chord (a_i0, b_s), a walked forward and b backward, one step
// along either at a time, each step a triangle on the chord it leaves and the one it reaches;
// m + n triangles back to the first chord, never on the same chord twice. Of all such
// walks, the one whose chords lie in no lower face and cost least (chordCost). When none does,
// vertices inside the cell may stand between a and b for runs of steps, each its own (entered
// and left by a triangle on the chord there; a run never spans all of a or all of b, which
// would join its vertex twice to one crossing), each dearer than any walk without it.
void zip(const double f[8], const uint8_t* a, int m, const uint8_t* b, int n, TrilinearCell& out) {
    std::array<double, 3> pa[kMcEdgeCount], pb[kMcEdgeCount];
    for (int i = 0; i < m; ++i) pa[i] = crossing(f, a[i]);
    for (int j = 0; j < n; ++j) pb[j] = crossing(f, b[j]);
    constexpr double kCentreCost = 1000.0;
    // Phases: out (on chords); in a run, just entered or stepped through, each as where the run
    // was entered (bit 0: on a's first chord, i = 0; bit 1: on b's, k = 0; then it is not left
    // on a's last, i = m, or b's, k = n).
    constexpr int kOut = 0, kEntered = 1, kThrough = 5, kPhases = 9;
    struct State {
        int phase, i, k;
    };
    constexpr int N = kMcEdgeCount + 1;
    double bestCost = kNoWay;
    State path[4 * N];
    int pathLength = 0, bestI0 = 0, bestS = 0;
    for (int i0 = 0; i0 < m; ++i0)
        for (int s0 = 0; s0 < n; ++s0) {
            auto A = [&](int i) { return (i0 + i) % m; };
            auto B = [&](int k) { return ((s0 - k) % n + n) % n; };
            auto chordAt = [&](int i, int k) { return chordCost(a[A(i)], b[B(k)], pa[A(i)], pb[B(k)]); };
            if (chordAt(0, 0) >= kNoWay) continue;  // the walk starts and ends on it
            double cost[kPhases][N][N];
            State from[kPhases][N][N];
            for (auto& c : cost)
                for (auto& r : c)
                    for (double& v : r) v = kNoWay;
            cost[kOut][0][0] = chordAt(0, 0);
            for (int i = 0; i <= m; ++i)
                for (int k = 0; k <= n; ++k) {
                    // A chord here (out, or entering or leaving a run), unless the walk may
                    // reach the same chord elsewhere: (0, k) is (m, k), (i, n) is (i, 0), and
                    // (m, 0) is (0, 0), the first and last.
                    const double here = (i == 0 && k > 0) || (i < m && k == n) || (i == m && k == 0) ? kNoWay
                                                                                                      : chordAt(i, k);
                    auto arrive = [&](int phase, double add, int fromPhase) {
                        if (i > 0 && cost[fromPhase][i - 1][k] + add < cost[phase][i][k])
                            cost[phase][i][k] = cost[fromPhase][i - 1][k] + add, from[phase][i][k] = {fromPhase, i - 1, k};
                        if (k > 0 && cost[fromPhase][i][k - 1] + add < cost[phase][i][k])
                            cost[phase][i][k] = cost[fromPhase][i][k - 1] + add, from[phase][i][k] = {fromPhase, i, k - 1};
                    };
                    auto set = [&](int phase, double c, State prev) {
                        if (c < cost[phase][i][k]) cost[phase][i][k] = c, from[phase][i][k] = prev;
                    };
                    if (here < kNoWay) arrive(kOut, here, kOut);
                    for (int g = 0; g < 4; ++g) {
                        arrive(kThrough + g, 0.0, kEntered + g);
                        arrive(kThrough + g, 0.0, kThrough + g);
                    }
                    if (here < kNoWay)  // a run left here
                        for (int g = 0; g < 4; ++g)
                            if (!((g & 1) && i == m) && !((g & 2) && k == n))
                                set(kOut, cost[kThrough + g][i][k] + here, {kThrough + g, i, k});
                    if (here < kNoWay && !(i == m && k == n))  // a run entered here
                        set(kEntered + ((i == 0 ? 1 : 0) | (k == 0 ? 2 : 0)), cost[kOut][i][k] + kCentreCost, {kOut, i, k});
                }
            if (!(cost[kOut][m][n] < bestCost)) continue;
            bestCost = cost[kOut][m][n];
            bestI0 = i0;
            bestS = s0;
            pathLength = 0;
            for (State at{kOut, m, n};;) {
                path[pathLength++] = at;
                if (at.phase == kOut && at.i == 0 && at.k == 0) break;
                at = from[at.phase][at.i][at.k];
            }
            std::reverse(path, path + pathLength);
        }
    if (bestCost >= kNoWay) {  // never: a run can take any chord (tests); the loops' discs instead
        out.unresolved = true;
        disc(f, a, m, out);
        disc(f, b, n, out);
        return;
    }
    auto A = [&](int i) { return (bestI0 + i) % m; };
    auto B = [&](int k) { return ((bestS - k) % n + n) % n; };
    auto inRun = [&](int phase) { return phase != kOut; };
    int c = -1;
    for (int s = 1; s < pathLength; ++s) {
        const State& was = path[s - 1];
        const State& now = path[s];
        if (now.i == was.i && now.k == was.k) {
            if (inRun(now.phase)) {  // a run entered: its vertex, at the mean of the crossings it joins
                std::array<double, 3> runA[2 * N], runB[2 * N];
                int na = 0, nb = 0;
                for (int t = s, i = -1, k = -1; t < pathLength && inRun(path[t].phase); ++t) {
                    if (path[t].i != i) runA[na++] = pa[A(i = path[t].i)];
                    if (path[t].k != k) runB[nb++] = pb[B(k = path[t].k)];
                }
                if (out.centreCount == kTrilinearMaxCentres) {  // never (tests): the discs instead
                    out.unresolved = true;
                    out.triangleCount -= s - 1;
                    disc(f, a, m, out);
                    disc(f, b, n, out);
                    return;
                }
                c = addCentre(out, runA, na, runB, nb);
                addTriangle(out, a[A(now.i)], c, b[B(now.k)]);
            } else {  // left
                addTriangle(out, a[A(now.i)], b[B(now.k)], c);
            }
        } else if (now.i > was.i) {  // a step along a
            addTriangle(out, a[A(was.i)], a[A(now.i)], inRun(now.phase) ? c : b[B(now.k)]);
        } else {  // a step along b
            addTriangle(out, inRun(now.phase) ? c : a[A(now.i)], b[B(now.k)], b[B(was.k)]);
        }
    }
}

}  // namespace

bool trilinearMayDiffer(int caseIndex) {
    if (mcAmbiguousFaces(caseIndex)) return true;
    double f[8];
    for (int c = 0; c < 8; ++c) f[c] = (caseIndex >> c & 1) ? 1.0 : -1.0;
    for (const bool above : {true, false}) {
        Groups<8> g = faceGroups(f, caseIndex, 0, above);
        int pieces = 0;
        for (int c = 0; c < 8; ++c) pieces += onSide(f[c], above) && g.find(c) == c;
        if (pieces >= 2) return true;
    }
    return false;
}

void trilinearCell(const double f[8], TrilinearCell& out) {
    out = TrilinearCell{};
    int caseIndex = 0;
    bool finite = true;
    for (int c = 0; c < 8; ++c) {
        caseIndex |= int(f[c] > 0) << c;
        finite = finite && std::isfinite(f[c]);
    }
    if (!finite) {  // not a trilinear interpolant (inf, NaN): the tables' cut
        const McTriangleCase& t = mcTriangleCase(caseIndex);
        out.triangleCount = t.triangleCount;
        std::copy_n(t.edges, 3 * t.triangleCount, out.edges);
        return;
    }
    const int joinAbove = joinedFaces(f, caseIndex);
    McPolygonCase loops;
    mcPolygonsJoined(caseIndex, joinAbove, loops);
    int first[kMcEdgeCount], size[kMcEdgeCount];
    for (int p = 0, at = 0; p < loops.polygonCount; at += size[p++]) {
        first[p] = at;
        size[p] = loops.vertexCount[p];
    }
    // Each loop parts one piece of each side (its pieces: the face groups of its first edge's
    // corners). A tunnel joins two pieces X, Y of a side inside: the tube runs between a loop of
    // X and a loop of Y whose other sides are one piece, which the tube's outside keeps whole
    // (a piece may have two loops: there is one such pair).
    int tubeWith[kMcEdgeCount];
    std::fill_n(tubeWith, loops.polygonCount, -1);
    {
        Groups<8> faces[2] = {faceGroups(f, caseIndex, joinAbove, false), faceGroups(f, caseIndex, joinAbove, true)};
        int piece[2][kMcEdgeCount];  // [above][loop]
        for (int p = 0; p < loops.polygonCount; ++p) {
            const int e = loops.edges[first[p]];
            const int a = kEdgeCorners[e][0], b = kEdgeCorners[e][1];
            const int up = f[a] > 0 ? a : b, down = f[a] > 0 ? b : a;
            piece[1][p] = faces[1].find(up);
            piece[0][p] = faces[0].find(down);
        }
        for (const bool above : {true, false}) {
            Groups<8> inside = interiorGroups(f, above);
            Groups<8>& side = faces[above];
            for (int x = 0; x < 8; ++x) {
                if (!onSide(f[x], above) || side.find(x) != x) continue;
                for (int y = x + 1; y < 8; ++y) {
                    if (!onSide(f[y], above) || side.find(y) != y || inside.find(y) != inside.find(x)) continue;
                    int pairs = 0, lx = -1, ly = -1;
                    for (int p = 0; p < loops.polygonCount; ++p)
                        for (int q = 0; q < loops.polygonCount; ++q)
                            if (piece[above][p] == x && piece[above][q] == y && piece[!above][p] == piece[!above][q])
                                ++pairs, lx = p, ly = q;
                    if (pairs != 1 || tubeWith[lx] != -1 || tubeWith[ly] != -1) {
                        out.unresolved = true;
                        continue;
                    }
                    tubeWith[lx] = ly;
                    tubeWith[ly] = lx;
                }
            }
        }
    }
    if (out.unresolved) std::fill_n(tubeWith, loops.polygonCount, -1);
    for (int p = 0; p < loops.polygonCount; ++p) {
        const uint8_t* v = loops.edges + first[p];
        if (tubeWith[p] == -1) {
            disc(f, v, size[p], out);
        } else if (tubeWith[p] > p) {
            zip(f, v, size[p], loops.edges + first[tubeWith[p]], size[tubeWith[p]], out);
        }
    }
}

void trilinearGradient(const double f[8], const double p[3], double gradient[3]) {
    gradient[0] = gradient[1] = gradient[2] = 0;
    for (int c = 0; c < 8; ++c) {
        double w[3], dw[3];
        for (int a = 0; a < 3; ++a) {
            const bool high = (c >> a) & 1;
            w[a] = high ? p[a] : 1 - p[a];
            dw[a] = high ? 1.0 : -1.0;
        }
        gradient[0] += f[c] * dw[0] * w[1] * w[2];
        gradient[1] += f[c] * w[0] * dw[1] * w[2];
        gradient[2] += f[c] * w[0] * w[1] * dw[2];
    }
}

}  // namespace vdiso
