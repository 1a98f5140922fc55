#include "core/extract_view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <exception>
#include <thread>
#include <utility>

#include <glm/geometric.hpp>

#include "core/brick_prefetcher.h"
#include "core/iso.h"
#include "core/mc_tables.h"
#include "core/minmax_tree.h"
#include "core/occlusion_pyramid.h"
#include "core/scan_convert.h"
#include "core/screen_box.h"
#include "core/sub_blocks.h"

namespace vdiso {

namespace {

using Clock = std::chrono::steady_clock;

struct Traversal {
    BrickSource& source;
    const Camera& camera;
    const ViewExtractOptions& options;
    TriangleMesh& mesh;
    PointSet& points;
    ViewExtractStats& stats;
    const VolumeInfo& volume;
    const BrickLayout& layout;
    BoxProjector projector;
    // The same projection from cell coordinates (the grid's affine map folded in), so a
    // cell's box costs no world-coordinate arithmetic: the per-cell test runs a million times.
    BoxProjector cellProjector;
    PixelProjector pixels;
    OcclusionPyramid pyramid;
    BrickExtractor extractor;
    EdgeVertexMap seams;
    const MinMaxTree& tree;  // shared by the strips
    double scanSeconds = 0;
    // The look-ahead for prefetching: a second cursor over the same front-to-back order, run
    // ahead of the traversal with tests 1-3 against the pyramid as it is now. Coverage only
    // grows, so every brick the traversal will acquire is found by it first; a brick it finds
    // may still be hidden by the time the traversal gets there (then it was read for nothing,
    // and counted).
    BrickPrefetcher prefetcher;
    std::vector<uint32_t> aheadStack;
    // Pixel centres [x0, x1] x [y0, y1] a screen box covers.
    struct PixelRect {
        int x0, y0, x1, y1;
        bool overlaps(const PixelRect& o) const {
            return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1;
        }
        PixelRect intersection(const PixelRect& o) const {
            return {std::max(x0, o.x0), std::max(y0, o.y0), std::min(x1, o.x1), std::min(y1, o.y1)};
        }
    };
    static constexpr size_t kNotPushed = SIZE_MAX;
    struct AheadBrick {
        uint32_t node;
        int64_t brick;
        PixelRect rect;
        size_t item = kNotPushed;  // in the prefetcher's list, once handed to it
    };
    std::deque<AheadBrick> aheadBricks;  // found ahead, in the traversal's order

    std::vector<int64_t> acquired;  // bricks, in the order extracted
    // The current brick is extracted whole (ViewStream::Use::Whole): hidden meta-cells too,
    // without points or per-cell tests.
    bool wholeBrick = false;
    bool cellTestsNow() const { return options.cellTests && !wholeBrick; }

    // Extracts what shows in pixel columns [column0, column1) of the image: the pyramid
    // starts with every other column covered, so the tests cull whatever shows only there.
    Traversal(BrickSource& s, const MinMaxTree& minMax, const Camera& c,
              const ViewExtractOptions& o, TriangleMesh& m, PointSet& p, ViewExtractStats& st,
              int column0, int column1)
        : source(s), camera(c), options(o), mesh(m), points(p), stats(st), volume(s.volume()),
          layout(s.layout()), projector(c),
          cellProjector(c.viewProjection() * s.volume().gridToWorld(), c.width, c.height),
          pixels(c), pyramid(c.width, c.height),
          extractor(s.volume(), s.layout(), o.metaCellSize), tree(minMax),
          prefetcher(s, size_t(std::max(o.prefetchBricks, 0)), o.prefetchReaders) {
        for (int y = 0; y < c.height; ++y) {
            if (column0 > 0) pyramid.coverSpan(y, 0, column0 - 1);
            if (column1 < c.width) pyramid.coverSpan(y, column1, c.width - 1);
        }
        pyramid.propagate();
    }

    // World box of the cells [lo, hi) (cell coordinates; clamped to the volume's cells).
    void worldBox(const int64_t lo[3], const int64_t hi[3], glm::dvec3& a, glm::dvec3& b) const {
        for (int k = 0; k < 3; ++k) {
            a[k] = volume.origin[k] + double(lo[k]) * volume.spacing[k];
            b[k] = volume.origin[k] + double(std::min(hi[k], volume.dims[k] - 1)) * volume.spacing[k];
        }
    }

    enum class Verdict { Culled, Done, Visible };
    enum class Cull { None, Range, Frustum, SubPixel, Occlusion };

    // The pixel centres i + 0.5 a screen box covers (possibly none, possibly off the image);
    // all of the image for a box crossing the near plane.
    PixelRect pixelRect(const ScreenBox& box) const {
        if (box.crossesNearPlane) return {0, 0, camera.width - 1, camera.height - 1};
        // Clamped a pixel beyond the image before the conversion: a box far off it has
        // coordinates no int holds. (NaN boxes never get here: cullScreenBox culls them.)
        auto column = [&](double x) { return int(std::clamp(x, -1.0, double(camera.width))); };
        auto row = [&](double y) { return int(std::clamp(y, -1.0, double(camera.height))); };
        return {column(std::ceil(box.left - 0.5)), row(std::ceil(box.top - 0.5)),
                column(std::floor(box.right - 0.5)), row(std::floor(box.bottom - 0.5))};
    }

    // Tests 2-3 of the header for the box [a, b]: the first that culls it, or None (a box
    // crossing the near plane is never culled).
    Cull cullBox(const glm::dvec3& a, const glm::dvec3& b, ScreenBox& box) const {
        box = options.estimateBox ? projector.estimateBox(a, b) : projector.exactBox(a, b);
        return cullScreenBox(box);
    }
    Cull cullScreenBox(const ScreenBox& box) const {
        if (box.crossesNearPlane) return Cull::None;  // refined, never culled
        // A camera whose numbers overflow the projection (an eye at 1e300, a fov of 1e-300
        // degrees) gives boxes of NaN: nothing of them can be drawn.
        if (!(box.left <= box.right && box.top <= box.bottom)) return Cull::Frustum;
        if (box.right < 0.5 || box.left > camera.width - 0.5 || box.bottom < 0.5 ||
            box.top > camera.height - 0.5)
            return Cull::Frustum;
        const PixelRect r = pixelRect(box);
        if (r.x0 > r.x1 || r.y0 > r.y1) return Cull::SubPixel;  // no pixel centre: nothing shows
        if (pyramid.isOccluded(r.x0, r.y0, r.x1, r.y1)) return Cull::Occlusion;
        return Cull::None;
    }

    // Tests 1-3 for the box [a, b] whose range is `range`.
    Cull cull(const BrickRange& range, const glm::dvec3& a, const glm::dvec3& b,
              ScreenBox& box) const {
        if (!rangeHoldsIso(range.minValue, range.maxValue, options.iso)) return Cull::Range;
        return cullBox(a, b, box);
    }

    // Tests 1-4 of the header for the box [a, b] whose range is `range`. `samplesLoaded`: the
    // box lies in the current brick, so a point can be placed on the surface itself; above
    // the bricks a sub-pixel node is refined down to one instead.
    Verdict test(const BrickRange& range, const glm::dvec3& a, const glm::dvec3& b,
                 bool samplesLoaded) {
        ++stats.nodesVisited;
        ScreenBox box;
        switch (cull(range, a, b, box)) {
            case Cull::Range: ++stats.culledByRange; return Verdict::Culled;
            case Cull::Frustum: ++stats.culledByFrustum; return Verdict::Culled;
            case Cull::SubPixel: ++stats.droppedSubPixel; return Verdict::Culled;
            case Cull::Occlusion: ++stats.culledByOcclusion; return Verdict::Culled;
            case Cull::None: break;
        }
        if (box.crossesNearPlane) return Verdict::Visible;
        // Fig. 4: a box under two pixels each way covering exactly one pixel centre is one
        // point; one covering two centres is refined like any other box.
        if (options.points && samplesLoaded && isSubPixel(box)) {
            if (const std::optional<glm::ivec2> p = subPixelPoint(box)) {
                // The point goes where the pixel centre's ray first meets the surface in the
                // box, with the field's normal there: it draws on the pixel the pyramid marks,
                // shaded as the triangles it stands for. No meeting: the surface covers no
                // pixel centre, and the box is dropped.
                glm::vec3 position, normal;
                if (p->x < 0 || p->y < 0 || p->x >= camera.width || p->y >= camera.height ||
                    pyramid.isCovered(p->x, p->y) || !rayHit(*p, a, b, position, normal)) {
                    ++stats.droppedSubPixel;
                    return Verdict::Culled;
                }
                points.positions.push_back(position);
                points.normals.push_back(normal);
                pyramid.coverSpan(p->y, p->x, p->x);
                pyramid.propagate();
                ++stats.points;
                return Verdict::Done;
            }
        }
        return Verdict::Visible;
    }

    bool rayHit(const glm::ivec2& pixel, const glm::dvec3& a, const glm::dvec3& b,
                glm::vec3& position, glm::vec3& normal) const {
        const glm::dvec3 nearPoint = pixels.unproject({pixel.x + 0.5, pixel.y + 0.5, 0.0});
        const glm::dvec3 farPoint = pixels.unproject({pixel.x + 0.5, pixel.y + 0.5, 1.0});
        const glm::dvec3 direction = farPoint - nearPoint;
        double t0 = 0.0, t1 = 1.0;  // slab intersection with the box
        for (int k = 0; k < 3; ++k) {
            if (direction[k] == 0.0) {
                if (nearPoint[k] < a[k] || nearPoint[k] > b[k]) return false;
                continue;
            }
            double ta = (a[k] - nearPoint[k]) / direction[k], tb = (b[k] - nearPoint[k]) / direction[k];
            if (ta > tb) std::swap(ta, tb);
            t0 = std::max(t0, ta);
            t1 = std::min(t1, tb);
        }
        return t0 <= t1 &&
               extractor.firstHit(nearPoint, direction, t0, t1, options.iso, position, normal);
    }

    // Scan-converts a polygon (SAGE §3.2), each vertex projected once, before its triangles
    // are appended. Cells arrive front to back, so a cell can be hidden by the cells before it
    // in its meta-cell. With cell tests, a polygon that covers no pixel centre left uncovered
    // is not kept: whatever it would draw lies behind what is drawn already or between pixel
    // centres, where the rasterizer makes no fragment either.
    static bool onPolygon(void* context, const uint32_t* vertices, int count) {
        auto& t = *static_cast<Traversal*>(context);
        glm::dvec2 v[kMcMaxPolygonVertices];
        for (int k = 0; k < count; ++k) {
            const glm::vec3& p = t.mesh.positions[vertices[k] - t.mesh.firstVertex];
            const glm::dvec3 s = t.pixels.project(glm::dvec3(p));
            // Behind the eye, clipped, or off any image a double can place: mark nothing.
            if (!(s.z >= 0.0 && s.z <= 1.0) || !std::isfinite(s.x) || !std::isfinite(s.y)) return true;
            v[k] = glm::dvec2(s.x, s.y);
        }
        bool coversNew = false;
        if (!t.options.bottomUp) {
            for (int k = 2; k < count; ++k) {
                const glm::dvec2 triangle[3] = {v[0], v[k - 1], v[k]};
                coversNew |= t.pyramid.insertTriangleTopDown(triangle);
            }
        } else if (t.options.scanPolygons) {
            coversNew = scanConvertPolygon(std::span<const glm::dvec2>(v, size_t(count)), t.pyramid);
            // Where a non-planar polygon's projection folds over itself its winding cancels,
            // yet its fan triangles, which are what gets drawn, cover those centres: before
            // dropping it, ask them (they mark only what they draw).
            for (int k = 2; k < count && !coversNew && t.cellTestsNow(); ++k) {
                const glm::dvec2 triangle[3] = {v[0], v[k - 1], v[k]};
                coversNew |= scanConvertPolygon(std::span<const glm::dvec2>(triangle, 3), t.pyramid);
            }
        } else {
            for (int k = 2; k < count; ++k) {
                const glm::dvec2 triangle[3] = {v[0], v[k - 1], v[k]};
                coversNew |= scanConvertPolygon(std::span<const glm::dvec2>(triangle, 3), t.pyramid);
            }
        }
        if (!t.cellTestsNow()) return true;
        // The rasterizer works in float on snapped coordinates, so a centre within a hair of
        // an edge may fall the other way there: such a polygon is kept as well (it marks
        // nothing; only coverage this side of the rounding is ever marked).
        for (int k = 2; k < count && !coversNew; ++k)
            coversNew = t.nearUncoveredCentre(v[0], v[k - 1], v[k]);
        t.stats.polygonsHidden += !coversNew;
        return coversNew;
    }

    // Whether an uncovered pixel centre lies inside the triangle or within kRasterSlack pixels
    // of each of its edges' lines. Degenerate triangles draw nothing.
    bool nearUncoveredCentre(const glm::dvec2& p0, const glm::dvec2& p1, const glm::dvec2& p2) const {
        constexpr double kRasterSlack = 1.0 / 64;  // GL's sub-pixel snapping is 1/256 or finer
        const double area2 = (p1.x - p0.x) * (p2.y - p0.y) - (p1.y - p0.y) * (p2.x - p0.x);
        if (!(area2 != 0.0)) return false;
        const glm::dvec2 corner[3] = {p0, p1, p2};
        double a[3], b[3], c[3];
        for (int e = 0; e < 3; ++e) {  // signed distance to edge e, positive inside
            const glm::dvec2 p = corner[e], q = corner[(e + 1) % 3];
            const double length = glm::length(q - p), sign = area2 > 0 ? 1.0 : -1.0;
            if (length == 0.0) return false;
            a[e] = -(q.y - p.y) * sign / length;
            b[e] = (q.x - p.x) * sign / length;
            c[e] = -(a[e] * p.x + b[e] * p.y);
        }
        const double xMin = std::min({p0.x, p1.x, p2.x}) - kRasterSlack;
        const double xMax = std::max({p0.x, p1.x, p2.x}) + kRasterSlack;
        const double yMin = std::min({p0.y, p1.y, p2.y}) - kRasterSlack;
        const double yMax = std::max({p0.y, p1.y, p2.y}) + kRasterSlack;
        // Clamped to the image before the conversion (a vertex far off it holds no int).
        const double w = camera.width, h = camera.height;
        const int x0 = int(std::clamp(std::ceil(xMin - 0.5), 0.0, w));
        const int x1 = int(std::clamp(std::floor(xMax - 0.5), -1.0, w - 1));
        const int y0 = int(std::clamp(std::ceil(yMin - 0.5), 0.0, h));
        const int y1 = int(std::clamp(std::floor(yMax - 0.5), -1.0, h - 1));
        if (x0 > x1 || y0 > y1 || pyramid.isOccluded(x0, y0, x1, y1)) return false;
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
                if (pyramid.isCovered(x, y)) continue;
                bool inside = true;
                for (int e = 0; e < 3 && inside; ++e)
                    inside = a[e] * (x + 0.5) + b[e] * (y + 0.5) + c[e] >= -kRasterSlack;
                if (inside) return true;
            }
        return false;
    }

    // The per-cell test: a cell shows only if its box covers a pixel centre not yet covered.
    static bool keepCell(void* context, int64_t x, int64_t y, int64_t z) {
        auto& t = *static_cast<Traversal*>(context);
        const glm::dvec3 a{double(x), double(y), double(z)};
        const ScreenBox box = t.options.estimateBox ? t.cellProjector.estimateUnitBox(a)
                                                    : t.cellProjector.exactBox(a, a + 1.0);
        const bool keep = t.cullScreenBox(box) == Cull::None;
        t.stats.cellsCulled += !keep;
        return keep;
    }

    // The meta-cells [lo, hi) of the current brick, front to back by halving (the same exact
    // order as the tree's), each tested and extracted when visible.
    void visitMetaCells(int64_t brick, const int lo[3], const int hi[3]) {
        const int n = extractor.metaCellsPerAxis(), M = extractor.metaCellSize();
        const std::vector<BrickRange>& ranges = extractor.currentRanges();
        BrickRange range{ranges[0].minValue, ranges[0].maxValue};
        bool first = true;
        for (int z = lo[2]; z < hi[2]; ++z)
            for (int y = lo[1]; y < hi[1]; ++y)
                for (int x = lo[0]; x < hi[0]; ++x) {
                    const BrickRange& r = ranges[size_t((z * n + y) * n + x)];
                    range = first ? r : BrickRange{std::min(range.minValue, r.minValue),
                                                   std::max(range.maxValue, r.maxValue)};
                    first = false;
                }
        const Dims3 c = layout.brickCoord(brick);
        int64_t cellLo[3], cellHi[3];
        for (int k = 0; k < 3; ++k) {
            cellLo[k] = c[k] * layout.brickSize + int64_t(lo[k]) * M;
            cellHi[k] = std::min<int64_t>(c[k] * layout.brickSize + int64_t(hi[k]) * M,
                                          c[k] * layout.brickSize + layout.cellsOnAxis(k, c[k]));
        }
        if (cellLo[0] >= cellHi[0] || cellLo[1] >= cellHi[1] || cellLo[2] >= cellHi[2]) return;
        glm::dvec3 a, b;
        worldBox(cellLo, cellHi, a, b);
        const bool single = hi[0] - lo[0] == 1 && hi[1] - lo[1] == 1 && hi[2] - lo[2] == 1;
        const uint32_t metaCell = uint32_t((lo[2] * n + lo[1]) * n + lo[0]);
        if (wholeBrick) {
            // Every active meta-cell is made; only those that show are scan-converted.
            ++stats.nodesVisited;
            if (!rangeHoldsIso(range.minValue, range.maxValue, options.iso)) {
                ++stats.culledByRange;
                return;
            }
            ScreenBox box;
            if (cullBox(a, b, box) != Cull::None) {
                extractUnseen(lo, hi);
                return;
            }
        } else if (test(range, a, b, true) != Verdict::Visible) {
            return;
        }
        if (single) {
            // Timed per meta-cell (extraction and scan conversion are interleaved polygon by
            // polygon; a clock read per polygon would cost more than it measures).
            const auto start = Clock::now();
            extractor.extractMetaCell(metaCell, options.iso, mesh, seams, &Traversal::onPolygon,
                                      this, cellTestsNow() ? &Traversal::keepCell : nullptr,
                                      &camera.eye);
            ++stats.metaCellsExtracted;
            if (options.bottomUp) pyramid.propagate();
            scanSeconds += std::chrono::duration<double>(Clock::now() - start).count();
            return;
        }
        int axis = 0;
        for (int k = 1; k < 3; ++k)
            if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
        const int mid = (lo[axis] + hi[axis]) / 2;
        int firstHi[3] = {hi[0], hi[1], hi[2]}, secondLo[3] = {lo[0], lo[1], lo[2]};
        firstHi[axis] = mid;
        secondLo[axis] = mid;
        const double split = volume.origin[axis] +
                             double(c[axis] * layout.brickSize + int64_t(mid) * M) * volume.spacing[axis];
        if (camera.eye[axis] < split) {
            visitMetaCells(brick, lo, firstHi);
            visitMetaCells(brick, secondLo, hi);
        } else {
            visitMetaCells(brick, secondLo, hi);
            visitMetaCells(brick, lo, firstHi);
        }
    }

    // The surface of the active meta-cells [lo, hi) of the current brick, which do not show:
    // made for a whole brick's chunk, not scan-converted.
    void extractUnseen(const int lo[3], const int hi[3]) {
        const int n = extractor.metaCellsPerAxis();
        const std::vector<BrickRange>& ranges = extractor.currentRanges();
        for (int z = lo[2]; z < hi[2]; ++z)
            for (int y = lo[1]; y < hi[1]; ++y)
                for (int x = lo[0]; x < hi[0]; ++x) {
                    const uint32_t metaCell = uint32_t((z * n + y) * n + x);
                    const BrickRange& r = ranges[metaCell];
                    if (!rangeHoldsIso(r.minValue, r.maxValue, options.iso)) continue;
                    extractor.extractMetaCell(metaCell, options.iso, mesh, seams);
                }
    }

    void nodeBox(const MinMaxNode& node, glm::dvec3& a, glm::dvec3& b) const {
        int64_t cellLo[3], cellHi[3];
        for (int k = 0; k < 3; ++k) {
            cellLo[k] = int64_t(node.lo[k]) * layout.brickSize;
            cellHi[k] = int64_t(node.hi[k]) * layout.brickSize;
        }
        worldBox(cellLo, cellHi, a, b);
    }

    // Pushes the children of node `index`, the far one first, so the near one pops first.
    void pushChildren(std::vector<uint32_t>& stack, uint32_t index) const {
        const std::vector<MinMaxNode>& nodes = tree.nodes();
        const MinMaxNode& node = nodes[index];
        const int axis = node.splitAxis;
        const int64_t mid = int64_t(nodes[index + 1].hi[axis]);
        const double split = volume.origin[axis] + double(mid * layout.brickSize) * volume.spacing[axis];
        const bool lowerIsNear = camera.eye[axis] < split;
        stack.push_back(lowerIsNear ? node.secondChild : index + 1);
        stack.push_back(lowerIsNear ? index + 1 : node.secondChild);
    }

    // Tests 1-3 for the sub-blocks of a brick whose box passed them (core/sub_blocks.h): does
    // any show? Known from the index, so a brick whose box passes only where it holds no
    // surface, or only where its surface is hidden, is not read. True when the source has no
    // sub-block ranges.
    bool subBlocksShow(int64_t brick) const {
        const std::span<const SubBlockCode> codes = source.subBlockCodes();
        if (codes.empty()) return true;
        const BrickRange whole = source.brickRanges()[size_t(brick)];
        const Dims3 c = layout.brickCoord(brick);
        const int C = subBlockCells(layout.brickSize);
        for (int s = 0; s < kSubBlocksPerBrick; ++s) {
            const BrickRange range = decodeSubBlockRange(codes[size_t(brick) * kSubBlocksPerBrick + size_t(s)], whole);
            if (!rangeHoldsIso(range.minValue, range.maxValue, options.iso)) continue;
            const int block[3] = {s % kSubBlocksPerAxis, s / kSubBlocksPerAxis % kSubBlocksPerAxis,
                                  s / (kSubBlocksPerAxis * kSubBlocksPerAxis)};
            int64_t lo[3], hi[3];
            for (int k = 0; k < 3; ++k) {
                const int64_t first = c[k] * layout.brickSize;
                lo[k] = first + int64_t(block[k]) * C;
                hi[k] = std::min(lo[k] + C, first + layout.cellsOnAxis(k, c[k]));
            }
            glm::dvec3 a, b;
            worldBox(lo, hi, a, b);
            ScreenBox box;
            if (cull(range, a, b, box) == Cull::None) return true;
        }
        return false;
    }

    // Tests 1-3 now, for the node and, for a brick, its sub-blocks; the node's screen box
    // in `box`.
    bool passes(uint32_t index, ScreenBox& box) const {
        const MinMaxNode& node = tree.nodes()[index];
        glm::dvec3 a, b;
        nodeBox(node, a, b);
        if (cull({node.minValue, node.maxValue}, a, b, box) != Cull::None) return false;
        return !node.isLeaf() || subBlocksShow(tree.brickOf(node));
    }

    // Moves the look-ahead on to the next brick that passes tests 1-3 now and hands it to the
    // prefetcher; false when the tree is exhausted.
    bool lookAheadOneBrick() {
        const std::vector<MinMaxNode>& nodes = tree.nodes();
        while (!aheadStack.empty()) {
            const uint32_t index = aheadStack.back();
            aheadStack.pop_back();
            const MinMaxNode& node = nodes[index];
            ScreenBox box;
            if (!passes(index, box)) continue;
            if (!node.isLeaf()) {
                pushChildren(aheadStack, index);
                continue;
            }
            aheadBricks.push_back({index, tree.brickOf(node), pixelRect(box)});
            return true;
        }
        return false;
    }

    // The traversal is about to acquire `brick`: bricks found ahead of it that it has not
    // asked for are hidden by now (their pins go). Those still ahead are tested again and
    // dropped once hidden (cancelled, if handed to the prefetcher but not read yet); the
    // look-ahead moves on; and bricks are handed to the prefetcher, in order, while each is
    // settled: where its screen box meets this brick's or any brick's before it, every pixel
    // is covered already, so that nothing drawn before its turn can hide it and reading it now
    // cannot be wasted. The next kNearBricks go regardless, so reads keep ahead where boxes
    // overlap, unless most of one's box lies in this brick's (closeups: it is likely behind
    // this one and hidden by it).
    void prefetchAround(int64_t brick) {
        constexpr size_t kNearBricks = 2;
        while (true) {
            while (!aheadBricks.empty() && aheadBricks.front().brick != brick) aheadBricks.pop_front();
            if (!aheadBricks.empty() || !lookAheadOneBrick()) break;
        }
        PixelRect current{0, 0, camera.width - 1, camera.height - 1};
        if (!aheadBricks.empty()) {
            current = aheadBricks.front().rect;
            if (aheadBricks.front().item != kNotPushed) prefetcher.consumed(aheadBricks.front().item);
            aheadBricks.pop_front();
        }
        std::erase_if(aheadBricks, [&](const AheadBrick& ahead) {
            ScreenBox box;
            if (passes(ahead.node, box)) return false;
            if (ahead.item != kNotPushed) prefetcher.cancel(ahead.item);
            return true;
        });
        while (aheadBricks.size() < size_t(options.prefetchBricks) && lookAheadOneBrick()) {
        }
        // Pixels of a rectangle on the image.
        auto pixelsOf = [&](const PixelRect& r) {
            const int64_t w = std::min(r.x1, camera.width - 1) - std::max(r.x0, 0) + 1;
            const int64_t h = std::min(r.y1, camera.height - 1) - std::max(r.y0, 0) + 1;
            return w > 0 && h > 0 ? w * h : int64_t(0);
        };
        // Most of a brick's box lies in the current brick's: it is likely behind, and hidden
        // once the current one is drawn (closeups), so it is not read on speculation.
        auto mostlyBehind = [&](const PixelRect& a, const PixelRect& b) {
            return a.overlaps(b) && 2 * pixelsOf(a.intersection(b)) > pixelsOf(a);
        };
        auto harmless = [&](const PixelRect& a, const PixelRect& b) {
            if (!a.overlaps(b)) return true;
            const PixelRect both = a.intersection(b);
            return pyramid.isOccluded(both.x0, both.y0, both.x1, both.y1);
        };
        for (size_t k = 0; k < aheadBricks.size(); ++k) {
            AheadBrick& ahead = aheadBricks[k];
            if (ahead.item != kNotPushed) continue;
            bool settled = harmless(ahead.rect, current);
            for (size_t j = 0; j < k && settled; ++j) settled = harmless(ahead.rect, aheadBricks[j].rect);
            if (!settled && (k >= kNearBricks || mostlyBehind(ahead.rect, current))) break;
            ahead.item = prefetcher.push(ahead.brick);
        }
    }

    void run() {
        const std::vector<MinMaxNode>& nodes = tree.nodes();
        std::vector<uint32_t> stack;
        if (!nodes.empty()) stack.push_back(0);
        if (options.prefetchBricks > 0) aheadStack = stack;
        while (!stack.empty()) {
            const uint32_t index = stack.back();
            stack.pop_back();
            const MinMaxNode& node = nodes[index];
            glm::dvec3 a, b;
            nodeBox(node, a, b);
            const Verdict v = test({node.minValue, node.maxValue}, a, b, false);
            if (v != Verdict::Visible) continue;
            if (!node.isLeaf()) {
                pushChildren(stack, index);
                continue;
            }
            const int64_t brick = tree.brickOf(node);
            if (!subBlocksShow(brick)) {
                ++stats.bricksCulledBySubBlocks;
                continue;
            }
            ViewStream::Use use = ViewStream::Use::Part;
            if (options.stream) {
                ScreenBox box;
                cullBox(a, b, box);
                const double cellPixels =
                    box.crossesNearPlane ? INFINITY
                                         : std::max(box.right - box.left, box.bottom - box.top) /
                                               double(layout.brickSize);
                if (!options.stream->beginBrick(brick, cellPixels, use)) {
                    stats.abandoned = true;
                    break;
                }
                // A chunk stands alone: no vertex is welded to another brick's.
                seams.clear();
            }
            if (options.prefetchBricks > 0) prefetchAround(brick);
            const auto start = Clock::now();
            const BrickHandle handle = source.acquire(brick);  // only now: it passed 1-3
            stats.brickWaitSeconds += std::chrono::duration<double>(Clock::now() - start).count();
            ++stats.bricksAcquired;
            acquired.push_back(brick);
            extractor.beginBrick(brick, handle.samples());
            const int n = extractor.metaCellsPerAxis();
            const int lo[3] = {0, 0, 0}, hi[3] = {n, n, n};
            wholeBrick = use == ViewStream::Use::Whole;
            visitMetaCells(brick, lo, hi);
            wholeBrick = false;
            if (options.stream) {
                stats.triangles += mesh.triangleCount();
                options.stream->endBrick(brick, use, mesh, points);
                mesh.firstVertex = mesh.nextVertex();
                mesh.clear();
                points.clear();
            }
        }
        prefetcher.stop();
        stats.cellsActive = extractor.counters().cellsActive;
        stats.bricksPrefetchedUnused = int64_t(prefetcher.skippedLoaded());
    }
};


// Column bounds of `strips` strips of the image with about as many active bricks (range
// holding iso) projecting into each: a stand-in for equal work.
std::vector<int> stripColumns(BrickSource& source, const Camera& camera, double iso, int strips) {
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
                        (double(c[k] * layout.brickSize) + 0.5 * layout.cellsOnAxis(k, c[k])) *
                            volume.spacing[k];
        const glm::dvec3 s = pixels.project(centre);
        if (s.z >= 0.0 && s.z <= 1.0 && s.x >= 0.0 && s.x < camera.width) centres.push_back(s.x);
    }
    std::sort(centres.begin(), centres.end());
    std::vector<int> columns{0};
    for (int k = 1; k < strips; ++k) {
        const int even = camera.width * k / strips;
        const int cut = centres.empty() ? even : int(centres[centres.size() * size_t(k) / size_t(strips)]);
        columns.push_back(std::clamp(cut, columns.back() + 1, camera.width - (strips - k)));
    }
    columns.push_back(camera.width);
    return columns;
}

}  // namespace

ViewExtractStats extractViewDependent(BrickSource& source, const Camera& camera,
                                      const ViewExtractOptions& options, TriangleMesh& mesh,
                                      PointSet& points, const ProgressFn& progress) {
    requireFiniteIso(options.iso);
    const auto start = Clock::now();
    ViewExtractStats stats;
    const uint64_t trianglesBefore = mesh.triangleCount();
    const int strips = std::clamp(options.threads, 1, camera.width);
    const MinMaxTree tree(source.layout(), source.brickRanges());
    // What is visible scales with the image, not the volume: room for a couple of triangles
    // per pixel saves regrowth copies (untouched reserved pages cost nothing).
    const size_t pixels = size_t(camera.width) * size_t(camera.height);
    if (strips == 1) {
        if (!options.stream) {
            mesh.indices.reserve(mesh.indices.size() + 6 * pixels);
            mesh.positions.reserve(mesh.positions.size() + pixels);
            mesh.normals.reserve(mesh.positions.capacity());
        }
        const uint32_t firstNewVertex = mesh.nextVertex();
        Traversal t(source, tree, camera, options, mesh, points, stats, 0, camera.width);
        t.run();
        // Vertices made for polygons that were then hidden belong to no triangle.
        if (options.cellTests && !options.stream) dropUnreferencedVertices(mesh, firstNewVertex);
        stats.scanSeconds = t.scanSeconds;
    } else {
        // Strips of the image in parallel, each its own traversal, pyramid and mesh; bricks
        // come through the one shared source, read once. A cell whose polygons cover new
        // pixel centres on both sides of a strip border is kept by both strips.
        const std::vector<int> columns = stripColumns(source, camera, options.iso, strips);
        struct Strip {
            TriangleMesh triangles;
            PointSet dots;
            ViewExtractStats counts;
            std::vector<int64_t> acquired;
            double scanSeconds = 0;
            std::exception_ptr error;
        };
        std::vector<Strip> parts(static_cast<size_t>(strips));
        ViewExtractOptions each = options;
        each.prefetchBricks = options.prefetchBricks / strips;
        auto runStrip = [&](int k) {
            Strip& part = parts[size_t(k)];
            try {
                if (!options.stream) {
                    const size_t share = pixels / size_t(strips);
                    part.triangles.indices.reserve(6 * share);
                    part.triangles.positions.reserve(share);
                    part.triangles.normals.reserve(share);
                }
                Traversal t(source, tree, camera, each, part.triangles, part.dots, part.counts,
                            columns[size_t(k)], columns[size_t(k) + 1]);
                t.run();
                if (options.cellTests && !options.stream) dropUnreferencedVertices(part.triangles, 0);
                part.acquired = std::move(t.acquired);
                part.scanSeconds = t.scanSeconds;
            } catch (...) {
                part.error = std::current_exception();
            }
        };
        std::vector<std::thread> threads;
        try {
            for (int k = 0; k < strips; ++k) threads.emplace_back(runStrip, k);
        } catch (...) {  // a thread could not start: let the others finish, then report it
            for (std::thread& t : threads) t.join();
            throw;
        }
        for (std::thread& t : threads) t.join();
        for (const Strip& part : parts)
            if (part.error) std::rethrow_exception(part.error);
        size_t vertices = 0, indices = 0;
        for (const Strip& part : parts) {
            vertices += part.triangles.positions.size();
            indices += part.triangles.indices.size();
        }
        mesh.positions.reserve(mesh.positions.size() + vertices);
        mesh.normals.reserve(mesh.normals.size() + vertices);
        mesh.indices.reserve(mesh.indices.size() + indices);
        std::vector<int64_t> acquired;
        for (Strip& part : parts) {
            const uint32_t offset = mesh.nextVertex();
            const TriangleMesh& m = part.triangles;
            mesh.positions.insert(mesh.positions.end(), m.positions.begin(), m.positions.end());
            mesh.normals.insert(mesh.normals.end(), m.normals.begin(), m.normals.end());
            for (uint32_t v : m.indices) mesh.indices.push_back(v + offset);
            const PointSet& d = part.dots;
            points.positions.insert(points.positions.end(), d.positions.begin(), d.positions.end());
            points.normals.insert(points.normals.end(), d.normals.begin(), d.normals.end());
            part.counts.scanSeconds = part.scanSeconds;
            stats += part.counts;
            stats.triangles += part.counts.triangles;
            acquired.insert(acquired.end(), part.acquired.begin(), part.acquired.end());
        }
        std::sort(acquired.begin(), acquired.end());
        stats.bricksAcquired = int64_t(std::unique(acquired.begin(), acquired.end()) - acquired.begin());
    }
    if (!options.stream) stats.triangles = mesh.triangleCount() - trianglesBefore;
    stats.extractSeconds = std::chrono::duration<double>(Clock::now() - start).count();
    if (progress) progress(1.0);
    return stats;
}

}  // namespace vdiso
