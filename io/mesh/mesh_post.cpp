#include "core/clock.h"
#include "io/mesh/mesh_post.h"

#include <algorithm>
#include <chrono>
#include <span>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/mesh_post/mesh_pieces.h"
#include "io/error.h"

namespace vdiso {

namespace {

struct VertexRecord {
    glm::vec3 position, normal;
};

}  // namespace

PostProcessedMesh::PostProcessedMesh(const std::string& outputPath, const BrickLayout& layout,
                                     const MeshPostOptions& options, MeshSink& out)
    : mLayout(layout), mOptions(options), mOut(out), mVertices(outputPath, ".vertices"),
      mIndices(outputPath, ".indices") {
    if (options.removesPieces()) mLabels.emplace(outputPath, ".pieces");
}

void PostProcessedMesh::startSlabs(int64_t untilZ) {
    while (int64_t(mSlabs.size()) <= untilZ) {
        Slab next;
        if (!mSlabs.empty()) {
            const Slab& last = mSlabs.back();
            next.firstVertex = last.firstVertex + last.vertexCount;
            next.firstIndex = last.firstIndex + last.indexCount;
        }
        mSlabs.push_back(next);
    }
}

void PostProcessedMesh::appendBrick(int64_t id, const TriangleMesh& part) {
    const int64_t z = mLayout.brickCoord(id)[2];
    if (z + 1 < int64_t(mSlabs.size()))
        throw std::invalid_argument("post-processing: bricks must come in increasing id order");
    startSlabs(z);
    Slab& slab = mSlabs.back();
    if (part.firstVertex != slab.firstVertex + slab.vertexCount)
        throw std::invalid_argument("post-processing: a brick's vertices do not follow the last brick's");
    for (size_t v = 0; v < part.vertexCount(); ++v) {
        const VertexRecord r{part.positions[v], part.normals[v]};
        mVertices.put(&r, sizeof r);
    }
    mIndices.put(part.indices.data(), part.indices.size() * sizeof(uint32_t));
    slab.vertexCount += uint32_t(part.vertexCount());
    slab.indexCount += part.indices.size();
}

TriangleMesh PostProcessedMesh::readSlab(int k, const std::vector<uint8_t>* keep) {
    const Slab& slab = mSlabs[size_t(k)];
    TriangleMesh mesh;
    mesh.firstVertex = slab.firstVertex;
    std::vector<VertexRecord> records(slab.vertexCount);
    mVertices.read(records.data(), records.size() * sizeof(VertexRecord),
                   uint64_t(slab.firstVertex) * sizeof(VertexRecord));
    mesh.positions.resize(records.size());
    mesh.normals.resize(records.size());
    for (size_t v = 0; v < records.size(); ++v) {
        mesh.positions[v] = records[v].position;
        mesh.normals[v] = records[v].normal;
    }
    mesh.indices.resize(slab.indexCount);
    mIndices.read(mesh.indices.data(), slab.indexCount * sizeof(uint32_t), slab.firstIndex * sizeof(uint32_t));
    if (keep) {
        std::vector<uint32_t> labels(slab.indexCount / 3);
        mLabels->read(labels.data(), labels.size() * sizeof(uint32_t), slab.firstIndex / 3 * sizeof(uint32_t));
        size_t to = 0;
        for (size_t t = 0; t < labels.size(); ++t) {
            if (!(*keep)[labels[t]]) continue;
            for (int c = 0; c < 3; ++c) mesh.indices[to++] = mesh.indices[3 * t + size_t(c)];
        }
        mesh.indices.resize(to);
    }
    return mesh;
}

MeshPostStats PostProcessedMesh::finish(const ProgressFn& progress) {
    startSlabs(mLayout.brickCounts[2] - 1);  // slabs past the last active brick, empty
    MeshPostStats stats;
    stats.slabs = int(mSlabs.size());
    stats.verticesIn = mSlabs.back().firstVertex + mSlabs.back().vertexCount;
    stats.trianglesIn = (mSlabs.back().firstIndex + mSlabs.back().indexCount) / 3;
    stats.spoolBytes = mVertices.size() + mIndices.size();
    const int slabs = stats.slabs;
    const double passes = mOptions.removesPieces() ? 2.0 : 1.0;
    auto report = [&](double pass, int k) {
        if (progress) progress((pass + double(k + 1) / slabs) / passes);
    };

    // Pieces: labelled slab by slab, then the labels kept.
    std::optional<std::vector<uint8_t>> keep;
    if (mOptions.removesPieces()) {
        const auto start = Clock::now();
        MeshPieces pieces;
        std::vector<uint32_t> labels;
        for (int k = 0; k < slabs; ++k) {
            const TriangleMesh slab = readSlab(k, nullptr);
            pieces.addSlab(slab.firstVertex, uint32_t(slab.vertexCount()), slab.indices, labels);
            mLabels->put(labels.data(), labels.size() * sizeof(uint32_t));
            report(0, k);
        }
        stats.spoolBytes += mLabels->size();
        stats.pieces = pieces.pieceCount();
        const uint32_t largest = pieces.largestPiece();
        if (largest != UINT32_MAX) stats.largestPieceTriangles = pieces.trianglesOf(largest);
        keep.emplace(pieces.labelCount(), uint8_t(0));
        for (uint32_t l = 0; l < pieces.labelCount(); ++l) {
            const uint32_t piece = pieces.pieceOf(l);
            const uint64_t triangles = pieces.trianglesOf(piece);
            (*keep)[l] = triangles > 0 && triangles >= mOptions.minPieceTriangles &&
                         (!mOptions.largestPiece || piece == largest);
            if (piece == l && (*keep)[l]) ++stats.piecesKept;
        }
        stats.piecesSeconds = secondsSince(start);
    }

    // A batch of slabs at a time, each shaped with the window around it (on several threads),
    // then written in order.
    const auto start = Clock::now();
    const int halo = haloSlabs(mOptions, mLayout.brickSize);
    stats.haloSlabs = halo;
    const int threads = std::max(1, mOptions.threads);
    const int batch = 2 * threads;
    tbb::task_arena arena(threads);
    SlabWriter writer;
    std::vector<TriangleMesh> held;  // slabs first .. first + held.size() - 1
    int first = 0;
    TriangleMesh out;
    for (int k0 = 0; k0 < slabs; k0 += batch) {
        const int k1 = std::min(slabs, k0 + batch);
        const int from = std::max(0, k0 - halo), to = std::min(slabs, k1 + halo);  // slabs needed
        held.erase(held.begin(), held.begin() + std::min<ptrdiff_t>(ptrdiff_t(held.size()), from - first));
        first = from;
        while (first + int(held.size()) < to)
            held.push_back(readSlab(first + int(held.size()), keep ? &*keep : nullptr));
        std::vector<ShapedSlab> shaped(size_t(k1 - k0));
        arena.execute([&] {
            tbb::parallel_for(k0, k1, [&](int k) {
                const int lo = std::max(0, k - halo), hi = std::min(slabs, k + halo + 1);
                const std::span<const TriangleMesh> window(held.data() + (lo - first), size_t(hi - lo));
                shaped[size_t(k - k0)] = shapeSlab(mOptions, window, size_t(k - lo));
            });
        });
        for (int k = k0; k < k1; ++k) {
            uint64_t inWindow = 0;
            for (int j = std::max(0, k - halo); j < std::min(slabs, k + halo + 1); ++j)
                inWindow += held[size_t(j - first)].triangleCount();
            stats.largestWindowTriangles = std::max(stats.largestWindowTriangles, inWindow);
            writer.write(shaped[size_t(k - k0)], out);
            stats.trianglesOut += out.triangleCount();
            mOut.append(out);
            report(passes - 1, k);
        }
    }
    stats.verticesOut = writer.verticesWritten();
    stats.finishSeconds = secondsSince(start);
    return stats;
}

}  // namespace vdiso
