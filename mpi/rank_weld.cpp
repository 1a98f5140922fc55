#include "mpi/rank_weld.h"

#include <stdexcept>
#include <string>

namespace vdiso::mpi {

RankMeshNumbering weldAcrossRanks(const Communicator& comm, const BrickPartition& partition,
                                  const VolumeInfo& volume, const BrickLayout& layout,
                                  const EdgeVertexMap& border, TriangleMesh& mesh) {
    const int me = comm.rank();
    const size_t ranks = size_t(comm.size());
    constexpr uint64_t kBorrowed = UINT64_MAX;
    // Borrowed vertices, by owner: the edge keys asked for and the local vertices they fill.
    std::vector<std::vector<uint64_t>> keys(ranks), vertices(ranks);
    std::vector<uint64_t> global(mesh.positions.size(), 0);
    border.forEach([&](uint64_t key, uint32_t v) {
        const int32_t owner = edgeOwner(volume.dims, layout, key, partition.partOfBrick, me);
        if (owner == me) return;
        keys[size_t(owner)].push_back(key);
        vertices[size_t(owner)].push_back(v);
        global[v] = kBorrowed;
    });

    RankMeshNumbering num;
    for (const auto& k : keys) num.borrowedVertices += k.size();
    num.ownedVertices = mesh.positions.size() - num.borrowedVertices;
    num.firstVertex = comm.exclusiveSum(num.ownedVertices);
    num.totalVertices = comm.sum(num.ownedVertices);
    num.triangles = mesh.triangleCount();
    num.firstTriangle = comm.exclusiveSum(num.triangles);
    num.totalTriangles = comm.sum(num.triangles);

    // Owned vertices keep their order, numbered from firstVertex; the others leave the mesh.
    size_t next = 0;
    for (size_t v = 0; v < global.size(); ++v) {
        if (global[v] == kBorrowed) continue;
        global[v] = num.firstVertex + next;
        mesh.positions[next] = mesh.positions[v];
        mesh.normals[next] = mesh.normals[v];
        ++next;
    }
    mesh.positions.resize(next);
    mesh.normals.resize(next);

    // Owners answer with the global numbers of the vertices asked for (kBorrowed: not found).
    const std::vector<std::vector<uint64_t>> asked = comm.exchange(keys);
    std::vector<std::vector<uint64_t>> answers(ranks);
    for (size_t r = 0; r < ranks; ++r)
        for (uint64_t key : asked[r]) {
            const uint32_t v = border.find(key);
            answers[r].push_back(v == UINT32_MAX ? kBorrowed : global[v]);
        }
    const std::vector<std::vector<uint64_t>> answered = comm.exchange(answers);
    for (size_t r = 0; r < ranks; ++r)
        if (int(r) != comm.rank()) num.bytesSent += (keys[r].size() + answers[r].size()) * sizeof(uint64_t);

    // Every rank reaches here: errors thrown now are the same collective step on each.
    if (num.totalVertices > UINT32_MAX)
        throw std::runtime_error("the mesh has " + std::to_string(num.totalVertices) +
                                 " vertices, more than PLY's 32-bit indices can number");
    for (size_t r = 0; r < ranks; ++r)
        for (size_t i = 0; i < answered[r].size(); ++i) {
            if (answered[r][i] == kBorrowed)
                throw std::runtime_error("rank " + std::to_string(r) + " has no vertex on edge " +
                                         std::to_string(keys[r][i]) + " (internal error)");
            global[vertices[r][i]] = answered[r][i];
        }
    for (uint32_t& index : mesh.indices) index = uint32_t(global[index]);
    mesh.firstVertex = uint32_t(num.firstVertex);
    return num;
}

}  // namespace vdiso::mpi
