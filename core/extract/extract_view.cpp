#include "core/extract/extract_view.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/clock.h"
#include "core/kernel/brick_kernel.h"
#include "core/check.h"
#include "core/extract/brick_look_ahead.h"
#include "core/extract/thin_part_draw.h"
#include "core/extract/traversal_cursor.h"
#include "core/lod/face_cap.h"
#include "core/lod/thin_parts.h"
#include "core/extract/image_strips.h"
#include "core/kernel/iso.h"
#include "core/kernel/mc_tables.h"
#include "core/kernel/meta_cell_walk.h"
#include "core/kernel/shown_meta_cell.h"
#include "core/trees/minmax_tree.h"
#include "core/view/corner_projection.h"
#include "core/view/occlusion_pyramid.h"
#include "core/view/polygon_coverage.h"
#include "core/scalar_type.h"
#include "core/view/sub_pixel_point.h"
#include "core/view/screen_box.h"
#include "core/view/view_culler.h"
#include "core/lod/view_levels.h"

namespace vdiso {

namespace {


enum class Verdict { Culled, Done, Visible };

// The meta-cell size a level is walked with: the options' M, halved (to no less than 4) while
// its meta-cells would span under 4 pixels even where the volume is nearest the eye. Meta-cells
// are what the sub-pixel point rule (core/view/sub_pixel_point.h) draws as points; where cells
// are far under a pixel (a distant view of a store without levels), meta-cells of 8 made 2.9
// primitives a covered pixel of an MRI where 4 make under 2. Elsewhere 8 pays a meta-cell's
// fixed costs half as often a triangle (core/kernel/brick_extractor.h).
int viewMetaCellSize(int M, double cellPixels) {
    while (M > 4 && double(M) * cellPixels < 4.0) M = std::max(M / 2, 4);
    return M;
}

template <class T>
struct BrickVisit;

// One walk of the tree, front to back, for one camera over the pixel columns
// [column0, column1) of the image (the whole image, or a strip of it: core/extract/image_strips.h).
// It owns the pyramid; its culler and look-ahead read it. Bricks are visited by BrickVisit,
// typed by the samples once per brick.
class ViewTraversal {
public:
    ViewTraversal(BrickSource& source, const MinMaxTree& tree, const Camera& camera,
                  const ViewExtractOptions& options, TriangleMesh& mesh, PointSet& points,
                  ExtractStats& stats, int column0, int column1)
        : mSource(source), mTree(tree), mCamera(camera), mOptions(options), mMesh(mesh), mPoints(points),
          mStats(stats), mPixels(camera), mPyramid(camera.width, camera.height),
          mLevels(source, tree, camera, mPyramid, options.iso, options.estimateBox, options.lodError),
          mCuller(mLevels.culler(0)),
          mCoverage(mPyramid, options.bottomUp, options.scanPolygons),
          mLookAhead(source, tree, mLevels, size_t(std::max(options.prefetchBricks, 0)), options.prefetchReaders,
                     size_t(std::max(options.prefetchNear, 0)), options.coverage != nullptr),
          mThinParts(mPixels, mPyramid) {
        mLevels.confineTo(options.region);
        coverOutsideStrip(mPyramid, column0, column1);
        mParts.resize(size_t(mLevels.count()));
    }

    // Extracts; returns the bricks acquired, in order.
    std::vector<int64_t> run();

private:
    template <class T>
    friend struct BrickVisit;

    void count(Cull cull);
    // Makes in mThinParts the points of coarse brick `at`'s lost thin parts that fall on pixels
    // not covered yet; drawThinParts() draws those still not covered.
    void thinPartPoints(const ViewLevels::Brick& at, const void* samples);
    void drawThinParts();

    BrickSource& mSource;
    const MinMaxTree& mTree;
    const Camera& mCamera;
    const ViewExtractOptions& mOptions;
    TriangleMesh& mMesh;
    PointSet& mPoints;
    ExtractStats& mStats;
    PixelProjector mPixels;
    OcclusionPyramid mPyramid;
    ViewLevels mLevels;
    const ViewCuller& mCuller;  // level 0's: the tree's
    PolygonCoverage mCoverage;
    // What extracting a level's bricks needs: its kernel's scratch, its own seam map (edge
    // keys are the level's grid's; vertices are welded within a level only) and its meta-cells'
    // corner projection.
    struct LevelParts {
        BrickExtractor extractor;
        EdgeVertexMap seams;
        CornerProjection corners;
    };
    std::vector<std::unique_ptr<LevelParts>> mParts;  // made at the level's first brick
    // Level `level`'s parts, made the first time: a view takes bricks of one or two levels, and
    // a level's kernel scratch is 560 KB zeroed (a frame culled at the root took 0.8 ms).
    LevelParts& parts(int level) {
        std::unique_ptr<LevelParts>& p = mParts[size_t(level)];
        if (!p) {
            const LevelSource& source = mLevels.source(level);
            const int M = viewMetaCellSize(mOptions.metaCellSize, mLevels.largestCellPixels(level));
            BrickExtractor extractor(source.volume(), source.layout(), M);
            CornerProjection corners(mLevels.culler(level).gridToClip(), mCamera.width, mCamera.height,
                                     extractor.metaCellSize());
            p = std::make_unique<LevelParts>(LevelParts{std::move(extractor), {}, std::move(corners)});
        }
        return *p;
    }
    TriangleMesh mCaps;  // streaming: the current brick's seam caps
    BrickLookAhead mLookAhead;
    ThinPartDraw mThinParts;
    // The visibility work's share of the time (ViewCounters).
    SampledTimer mCellTimer, mProjectionTimer, mCoverageTimer, mBoxTimer;
    SampledTimer mMetaCellTimer{1};  // every one: a meta-cell of 8^3 cells is long enough to time
};

// One brick of sample type T in the traversal: the visitor of its meta-cell walk
// (core/kernel/meta_cell_walk.h: each box tested, and extracted when visible), and the cell policy of
// core/kernel/shown_meta_cell.h that tests its cells and scan-converts its polygons
// (core/view/polygon_coverage.h), with the point rule for sub-pixel boxes (core/view/sub_pixel_point.h).
template <class T>
struct BrickVisit {
    ViewTraversal& t;
    const ViewCuller& culler;     // the brick's level's
    BrickExtractor& extractor;    //   "
    CornerProjection& corners;    //   "
    const BrickLayout& layout;    //   "
    int64_t brick;                // in the level's numbering
    BrickKernel<T> kernel;
    // The brick is extracted whole (ViewStream::Use::Whole): hidden meta-cells too, without
    // points or per-cell tests.
    bool whole;
    // The consumer holds the brick's surface (ViewStream::Use::Held): its polygons mark the
    // pyramid; no triangle is kept.
    bool held;
    bool cellTests;  // per-cell tests on and not whole
    glm::dvec3 eyeCell;
    MetaCellRangeCache::Ranges kept;         // from the options' range cache, if any
    const std::vector<BrickRange>& ranges;  // of the brick's meta-cells

    BrickVisit(ViewTraversal& traversal, const ViewLevels::Brick& at, const void* samples, ViewStream::Use use)
        : t(traversal), culler(traversal.mLevels.culler(at.level)),
          extractor(traversal.parts(at.level).extractor), corners(traversal.parts(at.level).corners),
          layout(traversal.mLevels.source(at.level).layout()), brick(at.local),
          kernel(extractor, at.local, samples, traversal.mOptions.iso, traversal.mMesh,
                 traversal.parts(at.level).seams),
          whole(use == ViewStream::Use::Whole), held(use == ViewStream::Use::Held),
          cellTests(traversal.mOptions.cellTests && traversal.mOptions.occlusion && !whole),
          eyeCell(kernel.eyeInCells(traversal.mCamera.eye)),
          kept(traversal.mOptions.rangeCache ? traversal.mOptions.rangeCache->get(at.id, at.local, extractor, samples)
                                             : nullptr),
          ranges(kept ? *kept : extractor.currentRanges()) {}

    // The corners of a visible meta-cell's crossed cells, projected for its cells' boxes and its
    // polygons' vertices (nothing is projected without occlusion culling: nothing is tested).
    void projectCorners(const int64_t first[3], const uint64_t* rows) {
        if (!t.mOptions.occlusion) return;
        t.mProjectionTimer(t.mStats.view.projectionSeconds, [&] {
            corners.project(first, rows);
            return 0;
        });
    }

    // The per-cell test: a cell shows only if its box covers a pixel centre not yet covered.
    bool keepCell(int x, int y, int z) {
        if (!cellTests) return true;
        const bool keep = t.mCellTimer(t.mStats.view.cellTestSeconds, [&] {
            PixelRect r;  // cullScreenBox's test of the cell's box, its rectangle rounded at once
            return !corners.cellRect(x, y, z, r) || (!r.empty() && !t.mPyramid.isOccluded(r.x0, r.y0, r.x1, r.y1));
        });
        t.mStats.view.cellsCulled += !keep;
        return keep;
    }

    // Scan-converts a polygon (SAGE §3.2) before its vertices are made; with cell tests, keeps
    // it only when it draws something (core/view/polygon_coverage.h).
    bool keepPolygon(const EdgePoint* outline, int count) {
        if (!t.mOptions.occlusion) return true;
        glm::dvec2 v[kMcMaxPolygonVertices];
        const bool placed = t.mProjectionTimer(t.mStats.view.projectionSeconds, [&] {
            for (int k = 0; k < count; ++k)
                if (!corners.place(outline[k].corner, outline[k].axis, outline[k].t, v[k])) return false;
            return true;
        });
        if (!placed) {
            // A vertex the camera cannot place: clipped away whole if every vertex lies behind
            // the near plane, else kept (in part in front: it marks nothing).
            for (int k = 0; k < count; ++k)
                if (!corners.behindNearPlane(outline[k].corner, outline[k].axis, outline[k].t)) return true;
            return false;
        }
        if (held && cellTests) {  // only its coverage counts
            t.mCoverageTimer(t.mStats.view.coverageSeconds, [&] {
                t.mCoverage.mark(v, count);
                return 0;
            });
            return false;
        }
        const bool draws =
            t.mCoverageTimer(t.mStats.view.coverageSeconds, [&] { return t.mCoverage.cover(v, count, cellTests); });
        t.mStats.view.polygonsHidden += !draws;
        return draws;
    }

    bool keepsTriangles() const { return !held; }

    // Tests 1-4 of core/extract/extract_view.h for a box of meta-cells [a, b] whose range is `range`.
    Verdict test(const BrickRange& range, const glm::dvec3& a, const glm::dvec3& b) {
        ++t.mStats.nodesVisited;
        ScreenBox box;
        const Cull cull = t.mBoxTimer(t.mStats.view.boxTestSeconds, [&] { return culler.cull(range, a, b, box); });
        if (cull != Cull::None) {
            t.count(cull);
            return Verdict::Culled;
        }
        // Fig. 4 (core/view/sub_pixel_point.h).
        if (!t.mOptions.points) return Verdict::Visible;
        switch (applyPointRule(box, a, b, kernel, t.mPixels, t.mPyramid, t.mOptions.occlusion, t.mPoints)) {
            case PointRule::NotAPoint: return Verdict::Visible;
            case PointRule::Dropped: ++t.mStats.view.droppedSubPixel; return Verdict::Culled;
            case PointRule::Drawn: break;
        }
        ++t.mStats.view.points;
        return Verdict::Done;
    }

    // core/kernel/meta_cell_walk.h: whether the box of meta-cells [lo, hi) is refined (or extracted,
    // when it is one): its range and tests 1-4, or, for a whole brick, its range alone (the
    // boxes that do not show are made without scan conversion).
    bool enter(const int lo[3], const int hi[3]) {
        const int M = extractor.metaCellSize();
        const BrickRange range = rangeOf(lo, hi);
        const Dims3 c = layout.brickCoord(brick);
        int64_t cellLo[3], cellHi[3];
        for (int k = 0; k < 3; ++k) {
            const int64_t first = c[k] * layout.brickSize;
            cellLo[k] = first + int64_t(lo[k]) * M;
            cellHi[k] = std::min<int64_t>(first + int64_t(hi[k]) * M, first + layout.cellsOnAxis(k, c[k]));
        }
        if (cellLo[0] >= cellHi[0] || cellLo[1] >= cellHi[1] || cellLo[2] >= cellHi[2]) return false;
        glm::dvec3 a, b;
        culler.worldBox(cellLo, cellHi, a, b);
        if (whole) {
            // Every active meta-cell is made; only those that show are scan-converted.
            ++t.mStats.nodesVisited;
            if (!rangeHoldsIso(range.minValue, range.maxValue, t.mOptions.iso)) {
                ++t.mStats.view.culledByRange;
                return false;
            }
            if (culler.cullScreenBox(culler.screenBox(a, b)) != Cull::None) {
                extractUnseen(lo, hi);
                return false;
            }
            return true;
        }
        return test(range, a, b) == Verdict::Visible;
    }

    // One meta-cell that shows, extracted and scan-converted. Timed by meta-cell (extraction
    // and scan conversion are interleaved polygon by polygon), each one: sampled one in 128,
    // a distant view's few hundred meta-cells gave a scan time of a few samples. (Meta-cells of
    // 4 cells had made the clock reads 2-3 % of a served frame: head1024, 90 K meta-cells.)
    void extract(const int lo[3]) {
        const int n = extractor.metaCellsPerAxis();
        t.mMetaCellTimer(t.mStats.view.scanSeconds, [&] {
            extractShownMetaCell(kernel, (lo[2] * n + lo[1]) * n + lo[0], *this, eyeCell);
            if (t.mOptions.bottomUp) t.mPyramid.propagate();
            return 0;
        });
        ++t.mStats.metaCellsActive;
    }

    // The range of meta-cells [lo, hi). (Taking the sub-block ranges of the store's index for
    // boxes of several meta-cells instead, and computing a brick's meta-cell ranges only for
    // those visited, was slower: the coarser ranges let more boxes through to the screen tests.)
    BrickRange rangeOf(const int lo[3], const int hi[3]) {
        const int n = extractor.metaCellsPerAxis();
        BrickRange range{std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest()};
        for (int z = lo[2]; z < hi[2]; ++z)
            for (int y = lo[1]; y < hi[1]; ++y)
                for (int x = lo[0]; x < hi[0]; ++x) {
                    const BrickRange& r = ranges[size_t((z * n + y) * n + x)];
                    range = {std::min(range.minValue, r.minValue), std::max(range.maxValue, r.maxValue)};
                }
        return range;
    }

    // The surface of the active meta-cells [lo, hi), which do not show: made for a whole
    // brick's chunk, not scan-converted.
    void extractUnseen(const int lo[3], const int hi[3]) {
        const int n = extractor.metaCellsPerAxis();
        for (int z = lo[2]; z < hi[2]; ++z)
            for (int y = lo[1]; y < hi[1]; ++y)
                for (int x = lo[0]; x < hi[0]; ++x) {
                    const int metaCell = (z * n + y) * n + x;
                    const BrickRange& r = ranges[size_t(metaCell)];
                    if (!rangeHoldsIso(r.minValue, r.maxValue, t.mOptions.iso)) continue;
                    kernel.extractMetaCell(metaCell);
                }
    }

    // `capFaces`: the faces to close (core/lod/face_cap.h), bits as ViewLevels::seamFaces; their
    // caps go to `caps`.
    void run(unsigned capFaces, TriangleMesh& caps) {
        const int n = extractor.metaCellsPerAxis();
        const int lo[3] = {0, 0, 0}, hi[3] = {n, n, n};
        walkMetaCells(lo, hi, extractor.metaCellSize(), eyeCell, *this);
        for (int face = 0; face < 6; ++face)
            if (capFaces & (1u << face)) appendFaceCap(kernel, face / 2, face % 2 == 1, caps);
    }
};

void ViewTraversal::count(Cull cull) {
    switch (cull) {
        case Cull::Range: ++mStats.view.culledByRange; break;
        case Cull::Frustum: ++mStats.view.culledByFrustum; break;
        case Cull::SubPixel: ++mStats.view.droppedSubPixel; break;
        case Cull::Occlusion: ++mStats.view.culledByOcclusion; break;
        case Cull::None: break;
    }
}

void ViewTraversal::thinPartPoints(const ViewLevels::Brick& at, const void* samples) {
    const int fine = std::max(at.level - 3, 0);  // sub-blocks of 1 to 4 coarse cells
    // A point on a pixel not covered now (the brick's own surface drawn) and with none waiting,
    // and a box whose pixels are not all covered now.
    auto wanted = [&](const glm::dvec3& position) { return mThinParts.take(position); };
    const ViewCuller& culler = mLevels.culler(at.level);
    auto shows = [&](const glm::dvec3& a, const glm::dvec3& b) {
        return culler.cullScreenBox(culler.screenBox(a, b)) == Cull::None;
    };
    const LevelSource& coarse = mLevels.source(at.level);
    auto find = [&] { return findLostParts(coarse, at.local, samples, mLevels.source(fine), at.level - fine, mOptions.iso); };
    LostPartMemo::Held kept;
    std::vector<LostPart> found;
    if (mOptions.lostParts)
        kept = mOptions.lostParts->get(at.id, mOptions.iso, find);
    else
        found = find();
    appendLostPartPoints(coarse, at.local, samples, kept ? *kept : found, mOptions.iso, mCamera.eye,
                         mThinParts.waiting(), wanted, shows);
}

void ViewTraversal::drawThinParts() {
    const int64_t drawn = mThinParts.draw(mPoints);
    mStats.view.points += drawn;
    mStats.view.thinPartPoints += drawn;
}

std::vector<int64_t> ViewTraversal::run() {
    std::vector<int64_t> acquired;
    const BrickLayout& layout = mSource.layout();
    TraversalCursor cursor(mTree, mLevels, mCuller);
    TraversalCursor::Step step;
    while (!cursor.ended()) {
        if (mOptions.coverage) mOptions.coverage->between(mPyramid, mStats.bricksActive);
        cursor.step(step);
        ++mStats.nodesVisited;
        switch (step.outcome) {
            case TraversalCursor::Outcome::OutsideRegion: ++mStats.view.culledByRegion; continue;
            case TraversalCursor::Outcome::Culled: count(step.cull); continue;
            case TraversalCursor::Outcome::Descended: continue;
            case TraversalCursor::Outcome::NotShown: ++mStats.view.bricksCulledBySubBlocks; continue;
            case TraversalCursor::Outcome::Brick: break;
        }
        const glm::dvec3& a = step.a;
        const glm::dvec3& b = step.b;
        const ViewLevels::Brick at = step.at;
        const int level = at.level;
        const int64_t brick = at.id;
        ViewStream::Use use = ViewStream::Use::Part;
        if (mOptions.stream) {
            const ScreenBox box = mCuller.screenBox(a, b);
            const double cellPixels =
                box.crossesNearPlane ? INFINITY
                                     : std::max(box.right - box.left, box.bottom - box.top) / double(layout.brickSize);
            if (!mOptions.stream->beginBrick(brick, level, cellPixels, use)) {
                mStats.view.abandoned = true;
                break;
            }
            // A chunk stands alone: no vertex is welded to another brick's.
            parts(level).seams.clear();
        }
        mLookAhead.beforeAcquire(brick);
        const auto start = Clock::now();
        const BrickHandle handle = mSource.acquire(brick);  // only now: it passed 1-3
        mStats.brickWaitSeconds += std::chrono::duration<double>(Clock::now() - start).count();
        ++mStats.bricksActive;
        mStats.view.coarseBricks += level > 0;
        acquired.push_back(brick);
        parts(level).extractor.beginBrick(at.local, handle.samples());
        // Seams between levels are capped where this brick meets another level for this
        // camera: with the mesh, or apart from a stream's brick output (they are the camera's).
        const unsigned capFaces = mOptions.capSeams ? mLevels.seamFaces(mTree.nodes()[step.node], level) : 0u;
        mStats.view.cappedFaces += std::popcount(capFaces);
        // Thin parts this level loses (core/lod/thin_parts.h), as points where nothing nearer
        // covers them; drawn at the end where nothing farther does either (a hole in a coarse
        // surface that the surface behind it fills is left to that: the points there would
        // shade it otherwise). Streamed, at the end of the brick.
        const size_t firstTriangle = mMesh.triangleCount();
        const uint32_t firstVertex = mMesh.nextVertex();
        visitScalarType(mSource.volume().type, [&](auto zero) {
            BrickVisit<decltype(zero)>(*this, at, handle.samples(), use)
                .run(capFaces, mOptions.stream ? mCaps : mMesh);
        });
        if (level > 0 && mOptions.points && use != ViewStream::Use::Whole) thinPartPoints(at, handle.samples());
        // Coarse cells are often as wide as the parts they cross (mesh.h).
        if (level > 0) {
            orientNormalsToFaces(mMesh, firstTriangle, firstVertex);
            splitVerticesFacingAway(mMesh, firstTriangle, glm::vec3(mCamera.eye));
        }
        if (mOptions.stream) {
            drawThinParts();  // a brick's output is final when handed over
            mStats.triangles += mMesh.triangleCount();
            mStats.vertices += mMesh.vertexCount();
            mStats.triangles += mCaps.triangleCount();
            mStats.vertices += mCaps.vertexCount();
            mOptions.stream->endBrick(brick, use, mMesh, mPoints, mCaps);
            mMesh.firstVertex = mMesh.nextVertex();
            mMesh.clear();
            mCaps.clear();
            mPoints.clear();
        }
    }
    drawThinParts();
    mLookAhead.stop();
    if (mOptions.coverage) mOptions.coverage->ended(mPyramid);
    for (const auto& level : mParts)
        if (level) mStats.cellsActive += level->extractor.counters().cellsActive;
    mStats.view.bricksPrefetchedUnused = int64_t(mLookAhead.readUnused());
    return acquired;
}

}  // namespace

ExtractStats extractViewDependent(BrickSource& source, const Camera& camera,
                                      const ViewExtractOptions& options, TriangleMesh& mesh,
                                      PointSet& points, const ProgressFn& progress) {
    requireFiniteIso(options.iso);
    const auto start = Clock::now();
    ExtractStats stats;
    const uint64_t trianglesBefore = mesh.triangleCount();
    const uint32_t verticesBefore = mesh.nextVertex();
    const int column0 = options.columnBegin, column1 = options.columnEnd < 0 ? camera.width : options.columnEnd;
    if (column0 < 0 || column1 <= column0 || column1 > camera.width)
        throw std::invalid_argument("view-dependent extraction: columns [" + std::to_string(column0) + ", " +
                                    std::to_string(column1) + ") are not a part of an image " +
                                    std::to_string(camera.width) + " pixels wide");
    const int strips = std::clamp(options.threads, 1, column1 - column0);
    if (options.coverage && strips > 1)
        throw std::invalid_argument("view-dependent extraction: merging coverage from elsewhere needs one thread");
    // With levels of detail, the tree knows every level's bricks and ranges (core/trees/minmax_tree.h).
    std::optional<MinMaxTree> built;
    if (options.tree)
        VDISO_CHECK_EQ(options.tree->levelCount(), source.levelCount());
    else
        built.emplace(source.levels(), source.brickRanges(), strips);
    const MinMaxTree& tree = options.tree ? *options.tree : *built;
    // What is visible scales with the image, not the volume: room for a couple of triangles
    // per pixel saves regrowth copies (untouched reserved pages cost nothing).
    const size_t pixels = size_t(camera.width) * size_t(camera.height);
    if (strips == 1) {
        if (!options.stream) {
            mesh.indices.reserve(mesh.indices.size() + 6 * pixels);
            mesh.positions.reserve(mesh.positions.size() + pixels);
            mesh.normals.reserve(mesh.positions.capacity());
        }
        ViewTraversal(source, tree, camera, options, mesh, points, stats, column0, column1).run();
    } else {
        const std::vector<int> columns = stripColumns(source, camera, options.iso, strips, column0, column1);
        std::vector<StripOutput> outputs(static_cast<size_t>(strips));
        ViewExtractOptions each = options;
        each.prefetchBricks = options.prefetchBricks / strips;
        runStrips(outputs, [&](int k, StripOutput& out) {
            if (!options.stream) {
                const size_t share = pixels / size_t(strips);
                out.triangles.indices.reserve(6 * share);
                out.triangles.positions.reserve(share);
                out.triangles.normals.reserve(share);
            }
            out.acquired = ViewTraversal(source, tree, camera, each, out.triangles, out.points, out.stats,
                                         columns[size_t(k)], columns[size_t(k) + 1])
                               .run();
        });
        stats = mergeStrips(outputs, mesh, points, source.layout().brickCount());
    }
    if (!options.stream) {
        stats.triangles = mesh.triangleCount() - trianglesBefore;
        stats.vertices = mesh.nextVertex() - verticesBefore;
    }
    stats.extractSeconds = std::chrono::duration<double>(Clock::now() - start).count();
    if (progress) progress(1.0);
    return stats;
}

ExtractStats streamViewDependent(BrickSource& source, const Camera& camera, const ViewExtractOptions& options) {
    if (!options.stream) throw std::invalid_argument("streamViewDependent: no stream to hand the bricks to");
    TriangleMesh brickMesh;  // each brick's, cleared once handed over
    PointSet brickPoints;
    return extractViewDependent(source, camera, options, brickMesh, brickPoints);
}

}  // namespace vdiso
