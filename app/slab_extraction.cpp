#include "app/slab_extraction.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/kernel/edge_vertex_map.h"

namespace vdiso {

namespace {

// Renumbers a layer's part (vertices from 0, its border vertices in `border`) in place into the
// output's numbers: a border vertex the layer before made (in `before`: edge key -> output
// number) takes that number and is dropped from the part, the others keep their order and are
// numbered from `next` on. `after` gets the output number of each of the part's border vertices.
// `values`, when given, one per vertex of the part, are kept as its vertices are.
void weld(TriangleMesh& part, std::vector<float>* values, const EdgeVertexMap& border, const EdgeVertexMap& before,
          uint32_t next, EdgeVertexMap& after) {
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
            if (values) (*values)[owned] = (*values)[v];
            ++owned;
        }
    if (values) values->resize(owned);
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

// Calls layer(rows, firstRow, L) for each layer L of bricks in [first, end) in order, with the
// slices it needs (its own and its ghosts) read once: the slices a layer shares with the one
// before are kept. The reader starts at the first layer's first slice.
template <class Layer>
void forEachLayer(SliceReader& slices, const BrickLayout& layout, int64_t first, int64_t end, Layer&& layer) {
    const VolumeInfo& info = slices.info();
    const size_t sliceBytes = size_t(info.sliceSamples()) * scalarSize(info.type);
    // Slices [w0, w1) of the volume: one layer's and its ghosts (B + 3 at most).
    std::vector<unsigned char> window(size_t(layout.side()) * sliceBytes);
    int64_t w0 = layout.clampSample(2, layout.firstSample(first)), w1 = w0;
    for (int64_t L = first; L < end; ++L) {
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
    BrickRange range = kNoRange;
    for (int64_t id = layout.brickId(0, 0, L); id < layout.brickId(0, 0, L + 1); ++id)
        range = unite(range, source.brickRanges()[size_t(id)]);
    return range;
}

// Parts of consecutive runs of layers, each numbered from 0 with its border vertices (edge key
// -> its number), joined in order into one numbering: each renumbered as it comes (weld), the
// arrays made at the end at their size.
class PartWelder {
public:
    void add(TriangleMesh&& part, std::vector<float>* values, const EdgeVertexMap& border) {
        mAfter.clear();
        weld(part, values, border, mBefore, mNext, mAfter);
        std::swap(mBefore, mAfter);
        mNext += uint32_t(part.positions.size());
        mTriangles += part.indices.size() / 3;
        mParts.push_back(std::move(part));
        if (values) mValues.push_back(std::move(*values));
    }
    // The border vertices of the part added last, in the joined numbers.
    const EdgeVertexMap& lastBorder() const { return mBefore; }
    const TriangleMesh& lastPart() const { return mParts.back(); }
    // The joined mesh, each part copied in and freed; the values likewise when given.
    void finish(TriangleMesh& mesh, std::vector<float>* values) {
        mesh.positions.resize(mNext);
        mesh.normals.resize(mNext);
        mesh.indices.resize(size_t(mTriangles) * 3);
        if (values) values->resize(mNext);
        size_t v = 0, k = 0;
        for (size_t p = 0; p < mParts.size(); ++p) {
            TriangleMesh& part = mParts[p];
            std::copy(part.positions.begin(), part.positions.end(), mesh.positions.begin() + ptrdiff_t(v));
            std::copy(part.normals.begin(), part.normals.end(), mesh.normals.begin() + ptrdiff_t(v));
            std::copy(part.indices.begin(), part.indices.end(), mesh.indices.begin() + ptrdiff_t(k));
            if (values) std::copy(mValues[p].begin(), mValues[p].end(), values->begin() + ptrdiff_t(v));
            v += part.positions.size();
            k += part.indices.size();
            part = TriangleMesh();
            if (values) mValues[p] = std::vector<float>();
        }
    }

private:
    std::vector<TriangleMesh> mParts;
    std::vector<std::vector<float>> mValues;
    EdgeVertexMap mBefore, mAfter;  // the border vertices of the part added last, and scratch
    uint32_t mNext = 0;
    uint64_t mTriangles = 0;
};

}  // namespace

BrickRange sliceRange(SliceReader& slices, int brickSize, int threads, const ProgressFn& progress) {
    const VolumeInfo& info = slices.info();
    const BrickLayout layout = layoutOf(info, brickSize);
    BrickRange range = kNoRange;
    forEachLayer(slices, layout, 0, layout.brickCounts[2], [&](const StridedSamples& rows, int64_t firstRow,
                                                               int64_t L) {
        const ArrayBrickSource source(rows, firstRow, info.dims[2], brickSize, info.spacing, threads);
        range = unite(range, layerRange(source, L));
        if (progress) progress(double(L + 1) / double(layout.brickCounts[2]));
    });
    return range;
}

SlabPart extractSlabPart(SliceReader& slices, const SlabExtractOptions& options, int64_t firstLayer, int64_t endLayer,
                         const ProgressFn& progress) {
    const VolumeInfo& info = slices.info();
    const BrickLayout layout = layoutOf(info, options.brickSize);
    if (firstLayer < 0 || endLayer > layout.brickCounts[2] || firstLayer >= endLayer)
        throw std::invalid_argument("extractSlabPart: layers [" + std::to_string(firstLayer) + ", " +
                                    std::to_string(endLayer) + ") are not a run of the volume's " +
                                    std::to_string(layout.brickCounts[2]));
    SlabPart part;
    PartWelder welder;
    forEachLayer(slices, layout, firstLayer, endLayer, [&](const StridedSamples& rows, int64_t firstRow, int64_t L) {
        ArrayBrickSource source(rows, firstRow, info.dims[2], options.brickSize, info.spacing, options.extract.threads);
        part.range = unite(part.range, layerRange(source, L));
        std::vector<int64_t> layer(size_t(layout.brickId(0, 0, L + 1) - layout.brickId(0, 0, L)));
        for (size_t k = 0; k < layer.size(); ++k) layer[k] = layout.brickId(0, 0, L) + int64_t(k);
        if (options.onlyBricks) {
            const std::vector<int64_t>& only = *options.onlyBricks;
            layer.assign(std::lower_bound(only.begin(), only.end(), layer.front()),
                         std::lower_bound(only.begin(), only.end(), layer.back() + 1));
        }
        EdgeVertexMap border;
        TriangleMesh layerMesh;
        ExtractStats s;
        if (!layer.empty()) {  // (a layer with none of onlyBricks is read for its ghosts, not meshed)
            FullExtractOptions o = options.extract;
            o.sink = nullptr;
            o.brickSink = nullptr;
            o.bricks = layer;
            o.borderVertices = &border;
            // Reported within the layer too: a layer of a large array is a second of work, and a
            // caller stops on an interrupt from its progress (Python's Ctrl-C).
            const double layers = double(endLayer - firstLayer);
            s = extractOctree(source, o, layerMesh, [&](double f) {
                if (progress) progress((double(L - firstLayer) + f) / layers);
            });
        } else if (progress) {
            progress(double(L + 1 - firstLayer) / double(endLayer - firstLayer));
        }
        welder.add(std::move(layerMesh), nullptr, border);
        if (L == firstLayer) part.border = welder.lastBorder();  // its face with the run before
        part.stats.nodesVisited += s.nodesVisited;
        part.stats.bricksActive += s.bricksActive;
        part.stats.metaCellsActive += s.metaCellsActive;
        part.stats.cellsActive += s.cellsActive;
        if (options.layerDone) options.layerDone(rows, firstRow, welder.lastPart().positions);
    });
    welder.lastBorder().forEach([&](uint64_t key, uint32_t v) {  // its face with the run after
        if (part.border.find(key) == UINT32_MAX) part.border.insert(key, v);
    });
    welder.finish(part.mesh, nullptr);
    part.stats.triangles = part.mesh.triangleCount();
    part.stats.vertices = part.mesh.positions.size();
    return part;
}

SlabExtractResult extractSlabs(SliceReader& slices, const SlabExtractOptions& options, TriangleMesh& mesh,
                               const ProgressFn& progress) {
    if (mesh.nextVertex() != 0) throw std::logic_error("extractSlabs: the mesh must be empty");
    const BrickLayout layout = layoutOf(slices.info(), options.brickSize);
    SlabPart part = extractSlabPart(slices, options, 0, layout.brickCounts[2], progress);
    mesh = std::move(part.mesh);
    return {part.stats, part.range};
}

void joinSlabParts(std::span<SlabPart> parts, std::span<std::vector<float>> values, TriangleMesh& mesh,
                   std::vector<float>* joinedValues) {
    if (!values.empty() && values.size() != parts.size())
        throw std::invalid_argument("joinSlabParts: values for some parts only");
    PartWelder welder;
    for (size_t k = 0; k < parts.size(); ++k) {
        if (!values.empty() && values[k].size() != parts[k].mesh.positions.size())
            throw std::invalid_argument("joinSlabParts: part " + std::to_string(k) + " has " +
                                        std::to_string(values[k].size()) + " values for " +
                                        std::to_string(parts[k].mesh.positions.size()) + " vertices");
        welder.add(std::move(parts[k].mesh), values.empty() ? nullptr : &values[k], parts[k].border);
        parts[k].border = EdgeVertexMap();
    }
    welder.finish(mesh, values.empty() ? nullptr : joinedValues);
}

}  // namespace vdiso
