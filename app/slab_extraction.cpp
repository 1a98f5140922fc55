#include "app/slab_extraction.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "core/kernel/edge_vertex_map.h"

namespace vdiso {

namespace {

// Renumbers a layer's part (vertices from 0, its border vertices in `border`) in place into the
// output's numbers: a border vertex the layer before made (in `before`: edge key -> output
// number) takes that number and is dropped from the part, the others keep their order and are
// numbered from `next` on. `after` gets the output number of each of the part's border vertices.
// The parts are kept apart until the end, so that the output is allocated once at its size.
void weld(TriangleMesh& part, const EdgeVertexMap& border, const EdgeVertexMap& before, uint32_t next,
          EdgeVertexMap& after) {
    constexpr uint32_t kOwned = UINT32_MAX;
    std::vector<uint32_t> number(part.positions.size(), kOwned);
    border.forEach([&](uint64_t key, uint32_t v) {
        if (const uint32_t n = before.find(key); n != UINT32_MAX) number[v] = n;
    });
    size_t owned = 0;
    for (size_t v = 0; v < number.size(); ++v)
        if (number[v] == kOwned) {
            number[v] = next + uint32_t(owned);
            part.positions[owned] = part.positions[v];
            part.normals[owned] = part.normals[v];
            ++owned;
        }
    part.positions.resize(owned);
    part.normals.resize(owned);
    for (uint32_t& index : part.indices) index = number[index];
    // A part extracted on one thread was reserved for a layer full of surface: held until the
    // end, its room would count against the address space (an RLIMIT_DATA counts it).
    auto fit = [](auto& array) {
        if (array.capacity() > array.size() + array.size() / 4) array.shrink_to_fit();
    };
    fit(part.positions);
    fit(part.normals);
    fit(part.indices);
    border.forEach([&](uint64_t key, uint32_t v) { after.insert(key, number[v]); });
}

// Calls layer(rows, firstRow, L) for each layer L of bricks in order, with the slices it needs
// (its own and its ghosts) read once: the slices a layer shares with the one before are kept.
template <class Layer>
void forEachLayer(SliceReader& slices, const BrickLayout& layout, Layer&& layer) {
    const VolumeInfo& info = slices.info();
    const size_t sliceBytes = size_t(info.sliceSamples()) * scalarSize(info.type);
    // Slices [w0, w1) of the volume: one layer's and its ghosts (B + 3 at most).
    std::vector<unsigned char> window(size_t(layout.side()) * sliceBytes);
    int64_t w0 = 0, w1 = 0;
    for (int64_t L = 0; L < layout.brickCounts[2]; ++L) {
        const int64_t a = layout.clampSample(2, layout.firstSample(L));
        const int64_t b = layout.clampSample(2, layout.firstSample(L) + layout.side() - 1) + 1;
        if (a > w0) {  // keep [a, w1): the slices this layer shares with the one before
            std::memmove(window.data(), window.data() + size_t(a - w0) * sliceBytes, size_t(w1 - a) * sliceBytes);
            w0 = a;
        }
        if (b > w1) {
            slices.read(window.data() + size_t(w1 - w0) * sliceBytes, b - w1);
            w1 = b;
        }
        StridedSamples rows;
        rows.data = window.data();
        rows.type = fileScalarOf(info.type);
        rows.dims = {info.dims[0], info.dims[1], w1 - w0};
        const int64_t bytes = int64_t(scalarSize(info.type));
        rows.strides = {bytes, bytes * info.dims[0], bytes * info.dims[0] * info.dims[1]};
        layer(rows, w0, L);
    }
    slices.finish();
}

BrickLayout layoutOf(const VolumeInfo& info, int brickSize) {
    const BrickLayout layout(info.dims, brickSize);
    if (const std::string problem = brickLayoutProblem(layout); !problem.empty())
        throw std::invalid_argument(problem);
    return layout;
}

// The union of the ranges of layer L's bricks.
BrickRange layerRange(const ArrayBrickSource& source, int64_t L) {
    const BrickLayout& layout = source.layout();
    BrickRange range{INFINITY, -INFINITY};
    for (int64_t id = layout.brickId(0, 0, L); id < layout.brickId(0, 0, L + 1); ++id) {
        const BrickRange& r = source.brickRanges()[size_t(id)];
        range = {std::min(range.minValue, r.minValue), std::max(range.maxValue, r.maxValue)};
    }
    return range;
}

}  // namespace

BrickRange sliceRange(SliceReader& slices, int brickSize, int threads, const ProgressFn& progress) {
    const VolumeInfo& info = slices.info();
    const BrickLayout layout = layoutOf(info, brickSize);
    BrickRange range{INFINITY, -INFINITY};
    forEachLayer(slices, layout, [&](const StridedSamples& rows, int64_t firstRow, int64_t L) {
        const ArrayBrickSource source(rows, firstRow, info.dims[2], brickSize, info.spacing, threads);
        const BrickRange r = layerRange(source, L);
        range = {std::min(range.minValue, r.minValue), std::max(range.maxValue, r.maxValue)};
        if (progress) progress(double(L + 1) / double(layout.brickCounts[2]));
    });
    return range;
}

SlabExtractResult extractSlabs(SliceReader& slices, const SlabExtractOptions& options, TriangleMesh& mesh,
                               const ProgressFn& progress) {
    if (mesh.nextVertex() != 0) throw std::logic_error("extractSlabs: the mesh must be empty");
    const VolumeInfo& info = slices.info();
    const BrickLayout layout = layoutOf(info, options.brickSize);
    SlabExtractResult result;
    std::vector<TriangleMesh> parts;
    EdgeVertexMap before, after;  // the layer before's border vertices, and this one's
    uint32_t next = 0;
    uint64_t triangles = 0;
    forEachLayer(slices, layout, [&](const StridedSamples& rows, int64_t firstRow, int64_t L) {
        ArrayBrickSource source(rows, firstRow, info.dims[2], options.brickSize, info.spacing, options.extract.threads);
        const BrickRange r = layerRange(source, L);
        result.range = {std::min(result.range.minValue, r.minValue), std::max(result.range.maxValue, r.maxValue)};
        std::vector<int64_t> layer(size_t(layout.brickId(0, 0, L + 1) - layout.brickId(0, 0, L)));
        for (size_t k = 0; k < layer.size(); ++k) layer[k] = layout.brickId(0, 0, L) + int64_t(k);
        FullExtractOptions o = options.extract;
        o.sink = nullptr;
        o.brickSink = nullptr;
        o.bricks = layer;
        EdgeVertexMap border;
        o.borderVertices = &border;
        TriangleMesh part;
        const ExtractStats s = extractOctree(source, o, part);
        after.clear();
        weld(part, border, before, next, after);
        std::swap(before, after);
        const TriangleMesh& p = parts.emplace_back(std::move(part));
        next += uint32_t(p.positions.size());
        triangles += p.indices.size() / 3;
        result.stats.nodesVisited += s.nodesVisited;
        result.stats.bricksActive += s.bricksActive;
        result.stats.metaCellsActive += s.metaCellsActive;
        result.stats.cellsActive += s.cellsActive;
        if (options.layerDone) options.layerDone(rows, firstRow, p.positions);
        if (progress) progress(double(L + 1) / double(layout.brickCounts[2]));
    });
    // The output at its size, each part copied in and freed.
    mesh.positions.resize(next);
    mesh.normals.resize(next);
    mesh.indices.resize(size_t(triangles) * 3);
    size_t v = 0, k = 0;
    for (TriangleMesh& p : parts) {
        std::copy(p.positions.begin(), p.positions.end(), mesh.positions.begin() + ptrdiff_t(v));
        std::copy(p.normals.begin(), p.normals.end(), mesh.normals.begin() + ptrdiff_t(v));
        std::copy(p.indices.begin(), p.indices.end(), mesh.indices.begin() + ptrdiff_t(k));
        v += p.positions.size();
        k += p.indices.size();
        p = TriangleMesh();
    }
    result.stats.triangles = triangles;
    result.stats.vertices = next;
    return result;
}

}  // namespace vdiso
