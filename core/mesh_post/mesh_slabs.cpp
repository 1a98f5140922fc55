#include "core/mesh_post/mesh_slabs.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>

#include <meshoptimizer.h>

#include "core/mesh_post/mesh_smooth.h"

namespace vdiso {

namespace {

constexpr uint32_t kNone = UINT32_MAX;

// The window's slabs as one mesh numbered from the first slab's first vertex: every vertex, and
// the triangles whose vertices are all held (a first slab's triangles may also use the slab
// before it, which is not: those go, at the window's far edge, where no result is kept).
struct WindowMesh {
    uint32_t base = 0;
    std::vector<glm::vec3> positions, normals;
    std::vector<uint32_t> indices;
};

WindowMesh gather(std::span<const TriangleMesh> window) {
    WindowMesh w;
    w.base = window.front().firstVertex;
    for (const TriangleMesh& slab : window) {
        if (slab.firstVertex != w.base + w.positions.size())
            throw std::invalid_argument("mesh slabs are not numbered consecutively");
        w.positions.insert(w.positions.end(), slab.positions.begin(), slab.positions.end());
        w.normals.insert(w.normals.end(), slab.normals.begin(), slab.normals.end());
    }
    const uint32_t end = w.base + uint32_t(w.positions.size());
    for (const TriangleMesh& slab : window) {
        for (size_t t = 0; t < slab.indices.size(); t += 3) {
            const uint32_t* v = &slab.indices[t];
            if (v[0] < w.base || v[1] < w.base || v[2] < w.base) continue;
            if (v[0] >= end || v[1] >= end || v[2] >= end)
                throw std::invalid_argument("a mesh slab's triangle refers to a later slab's vertex");
            for (int c = 0; c < 3; ++c) w.indices.push_back(v[c] - w.base);
        }
    }
    return w;
}

// The vertices on an open edge (used by one of the triangles only): marked in `border`.
void markOpenEdgeVertices(std::span<const uint32_t> indices, std::vector<bool>& border) {
    std::vector<uint64_t> edges;
    edges.reserve(indices.size());
    for (size_t t = 0; t < indices.size(); t += 3)
        for (int c = 0; c < 3; ++c) {
            const uint32_t a = indices[t + size_t(c)], b = indices[t + size_t((c + 1) % 3)];
            edges.push_back(uint64_t(std::min(a, b)) << 32 | std::max(a, b));
        }
    std::sort(edges.begin(), edges.end());
    for (size_t i = 0; i < edges.size();) {
        size_t j = i + 1;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i == 1) border[edges[i] >> 32] = border[edges[i] & 0xffffffffu] = true;
        i = j;
    }
}

// Removes the triangles that come in pairs on the same three vertices, facing opposite ways:
// a fin of no volume that the simplifier's collapses sometimes fold out of a thin part (it then
// hangs off the surface, its edges used by four triangles). A triangle repeated the same way
// is kept once.
void removeFins(std::vector<uint32_t>& indices) {
    struct Face {
        uint32_t v[3];
        bool flipped;  // v is the triangle rotated to start at its least vertex, then b and c swapped
        size_t at;
    };
    std::vector<Face> faces(indices.size() / 3);
    for (size_t t = 0; t < faces.size(); ++t) {
        uint32_t a = indices[3 * t], b = indices[3 * t + 1], c = indices[3 * t + 2];
        while (a > b || a > c) std::tie(a, b, c) = std::make_tuple(b, c, a);
        faces[t] = b < c ? Face{{a, b, c}, false, t} : Face{{a, c, b}, true, t};
    }
    auto sameVertices = [](const Face& x, const Face& y) {
        return x.v[0] == y.v[0] && x.v[1] == y.v[1] && x.v[2] == y.v[2];
    };
    std::sort(faces.begin(), faces.end(), [](const Face& x, const Face& y) {
        return std::tie(x.v[0], x.v[1], x.v[2], x.flipped, x.at) < std::tie(y.v[0], y.v[1], y.v[2], y.flipped, y.at);
    });
    std::vector<bool> drop(faces.size(), false);
    for (size_t i = 0; i < faces.size();) {
        size_t j = i;
        int facing[2] = {0, 0};
        while (j < faces.size() && sameVertices(faces[i], faces[j])) ++facing[faces[j++].flipped];
        // One of each way cancels; of what is left, one stays.
        const int pairs = std::min(facing[0], facing[1]);
        int keepFlipped = facing[1] > pairs ? 1 : 0, keepUnflipped = facing[0] > pairs ? 1 : 0;
        for (size_t k = i; k < j; ++k) {
            int& keep = faces[k].flipped ? keepFlipped : keepUnflipped;
            if (keep > 0) --keep;
            else drop[faces[k].at] = true;
        }
        i = j;
    }
    size_t to = 0;
    for (size_t t = 0; t < faces.size(); ++t)
        if (!drop[t])
            for (int c = 0; c < 3; ++c) indices[to++] = indices[3 * t + size_t(c)];
    indices.resize(to);
}

// Keeps about `ratio` of the triangles (3 indices each, into `positions`) by meshoptimizer's
// edge collapses, keeping as they are the triangles that touch the border (a vertex on an
// open edge: the slab's faces, the volume's). Locking the border vertices alone is not enough:
// both slabs could then collapse onto the same three border vertices, each making the flat
// triangle between them, and the pair would hang off the surface as a fin. The triangles kept
// leave the next ring of vertices on the border of what the simplifier gets, which it locks.
void decimateKeepingBorder(std::vector<uint32_t>& indices, std::span<const glm::vec3> positions,
                           double ratio) {
    if (indices.empty()) return;
    std::vector<bool> border(positions.size(), false);
    markOpenEdgeVertices(indices, border);
    std::vector<uint32_t> compact(positions.size(), kNone), original, kept, simplified;
    std::vector<glm::vec3> used;
    for (size_t t = 0; t < indices.size(); t += 3) {
        const uint32_t* v = &indices[t];
        if (border[v[0]] || border[v[1]] || border[v[2]]) {
            kept.insert(kept.end(), v, v + 3);
            continue;
        }
        for (int c = 0; c < 3; ++c) {
            uint32_t& n = compact[v[c]];
            if (n == kNone) {
                n = uint32_t(used.size());
                used.push_back(positions[v[c]]);
                original.push_back(v[c]);
            }
            simplified.push_back(n);
        }
    }
    const size_t target = size_t(std::max<long long>(0, std::llround(double(indices.size() / 3) * ratio) -
                                                            (long long)(kept.size() / 3))) * 3;
    std::vector<uint32_t> result(simplified.size());
    // The error bound is relative to the slab's extent: 1 lets the count alone decide.
    const size_t count =
        simplified.empty() ? 0
                           : meshopt_simplify(result.data(), simplified.data(), simplified.size(), &used[0].x,
                                              used.size(), sizeof(glm::vec3), target, 1.0f,
                                              meshopt_SimplifyLockBorder, nullptr);
    result.resize(count);
    removeFins(result);
    indices = std::move(kept);
    for (uint32_t v : result) indices.push_back(original[v]);
}

}  // namespace

int haloSlabs(const MeshPostOptions& options, int brickSize) {
    // Smoothing reaches 2 * iterations + 1 edges (the last to know which edges are open), each at
    // most a cell; a slab's vertices lie within its brick layer, faces included.
    const int reach = options.smoothIterations > 0 ? 2 * options.smoothIterations + 1 : 0;
    return std::max(1, reach / brickSize + 1);
}

ShapedSlab shapeSlab(const MeshPostOptions& options, std::span<const TriangleMesh> window, size_t center) {
    const TriangleMesh& slab = window[center];
    WindowMesh w = gather(window);
    const uint32_t first = slab.firstVertex - w.base, count = uint32_t(slab.vertexCount());
    if (options.smoothIterations > 0) {
        smoothTaubin(w.positions, w.indices, options.smoothIterations);
        triangleNormals(w.positions, w.indices, w.normals, first, count);
    }
    ShapedSlab shaped;
    shaped.firstVertex = slab.firstVertex;
    shaped.positions.assign(w.positions.begin() + first, w.positions.begin() + first + count);
    shaped.normals.assign(w.normals.begin() + first, w.normals.begin() + first + count);
    // The slab's triangles, in window numbering while decimated.
    shaped.indices.assign(slab.indices.begin(), slab.indices.end());
    for (uint32_t& v : shaped.indices) {
        if (v < w.base) throw std::invalid_argument("a mesh slab's triangle refers to a vertex before the slab it follows");
        v -= w.base;
    }
    if (options.decimateRatio < 1.0) decimateKeepingBorder(shaped.indices, w.positions, options.decimateRatio);
    for (uint32_t& v : shaped.indices) v += w.base;
    shaped.usedByNext.assign(count, false);
    if (center + 1 < window.size())
        for (uint32_t v : window[center + 1].indices)
            if (v - slab.firstVertex < count) shaped.usedByNext[v - slab.firstVertex] = true;
    return shaped;
}

void SlabWriter::write(const ShapedSlab& slab, TriangleMesh& out) {
    // Its vertices written: those its triangles or the next slab's use.
    const uint32_t first = slab.firstVertex, count = uint32_t(slab.positions.size());
    std::vector<uint32_t> numbers(count, kNone);
    for (uint32_t k = 0; k < count; ++k)
        if (slab.usedByNext[k]) numbers[k] = 0;
    for (uint32_t v : slab.indices)
        if (v - first < count) numbers[v - first] = 0;
    out.clear();
    out.firstVertex = uint32_t(mWritten);
    for (uint32_t k = 0; k < count; ++k) {
        if (numbers[k] == kNone) continue;
        numbers[k] = out.nextVertex();
        out.positions.push_back(slab.positions[k]);
        out.normals.push_back(slab.normals[k]);
    }
    mWritten = out.nextVertex();
    out.indices.resize(slab.indices.size());
    for (size_t i = 0; i < slab.indices.size(); ++i) {
        const uint32_t v = slab.indices[i];
        const uint32_t n = v - first < count ? numbers[v - first]
                           : v - mPreviousFirst < mPreviousNumbers.size() ? mPreviousNumbers[v - mPreviousFirst]
                                                                          : kNone;
        if (n == kNone)
            throw std::invalid_argument("a mesh slab's triangle refers to a vertex neither it nor the slab "
                                        "before it has written");
        out.indices[i] = n;
    }
    mPreviousNumbers = std::move(numbers);
    mPreviousFirst = first;
}

}  // namespace vdiso
