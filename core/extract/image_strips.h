// Vertical strips of the image for the view-dependent traversal on several threads
// (ViewExtractOptions::threads): one traversal per strip, each with its own pyramid and mesh,
// bricks read once through the shared source.
//
// A strip's pyramid starts with the rest of the image covered, so its tests cull whatever
// shows only elsewhere. A cell whose polygons cover new pixel centres on both sides of a
// border is kept by both strips (its triangles appear twice: 0.3% more for SAGE, 1% for WISE).
#pragma once

#include <exception>
#include <thread>
#include <vector>

#include "core/brick_source.h"
#include "core/camera.h"
#include "core/extract/extract_view.h"
#include "core/mesh.h"
#include "core/thread_name.h"
#include "core/view/occlusion_pyramid.h"

namespace vdiso {

// Column bounds (strips + 1 of them, from column0 to column1) of `strips` strips of the columns
// [column0, column1) with about as many active bricks (range holding iso) projecting into each:
// a stand-in for equal work. strips <= column1 - column0.
std::vector<int> stripColumns(const BrickSource& source, const Camera& camera, double iso, int strips, int column0,
                              int column1);

// Covers every pixel outside columns [column0, column1) and propagates.
void coverOutsideStrip(OcclusionPyramid& pyramid, int column0, int column1);

// What one strip made.
struct StripOutput {
    TriangleMesh triangles;
    PointSet points;
    ExtractStats stats;
    std::vector<int64_t> acquired;  // bricks, in the order extracted
    std::exception_ptr error;
};

// Runs strip(k, output[k]) for each strip, the first on the calling thread and each other on a
// thread of its own, and waits for all; then rethrows the first strip's exception, if any.
template <class Strip>
void runStrips(std::vector<StripOutput>& outputs, Strip&& strip);

// Appends the strips' meshes and points in strip order; returns their statistics summed, with
// bricksActive, and view.coarseBricks (those numbered from `firstCoarseBrick`: coarser levels
// of detail), counting a brick read by two strips once.
ExtractStats mergeStrips(std::vector<StripOutput>& outputs, TriangleMesh& mesh, PointSet& points,
                         int64_t firstCoarseBrick);

template <class Strip>
void runStrips(std::vector<StripOutput>& outputs, Strip&& strip) {
    std::vector<std::thread> threads;
    auto run = [&](size_t k) {
        try {
            strip(int(k), outputs[k]);
        } catch (...) {
            outputs[k].error = std::current_exception();
        }
    };
    try {
        for (size_t k = 1; k < outputs.size(); ++k)
            threads.emplace_back([&run, k] {
                nameThisThread("vdiso-strip");
                run(k);
            });
    } catch (...) {  // a thread could not start: let the others finish, then report it
        for (std::thread& t : threads) t.join();
        throw;
    }
    if (!outputs.empty()) run(0);
    for (std::thread& t : threads) t.join();
    for (const StripOutput& output : outputs)
        if (output.error) std::rethrow_exception(output.error);
}

}  // namespace vdiso
