#include "tests/extract_test_util.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include <glm/geometric.hpp>

#include "core/trees/sub_blocks.h"

namespace vdiso::test {

MemoryBrickSource::MemoryBrickSource(const Dims3& dims, ScalarType type, int brickSize,
                                     const std::function<double(int64_t, int64_t, int64_t)>& f)
    : mLayout(dims, brickSize) {
    mInfo.dims = dims;
    mInfo.type = type;
    mSamples.resize(mInfo.byteSize());
    visitScalarType(type, [&](auto zero) {
        using T = decltype(zero);
        T* p = reinterpret_cast<T*>(mSamples.data());
        for (int64_t z = 0; z < dims[2]; ++z)
            for (int64_t y = 0; y < dims[1]; ++y)
                for (int64_t x = 0; x < dims[0]; ++x) {
                    const double v = f(x, y, z);
                    *p++ = std::is_integral_v<T> ? T(std::lround(v)) : T(v);
                }
        const T* volume = reinterpret_cast<const T*>(mSamples.data());
        const int side = mLayout.side();
        for (int64_t id = 0; id < mLayout.brickCount(); ++id) {
            const Dims3 c = mLayout.brickCoord(id);
            std::vector<unsigned char> brick(size_t(mLayout.samplesPerBrick()) * sizeof(T));
            T* b = reinterpret_cast<T*>(brick.data());
            double lo = INFINITY, hi = -INFINITY;
            for (int lz = 0; lz < side; ++lz)
                for (int ly = 0; ly < side; ++ly)
                    for (int lx = 0; lx < side; ++lx) {
                        const int64_t gx = mLayout.clampSample(0, mLayout.firstSample(c[0]) + lx);
                        const int64_t gy = mLayout.clampSample(1, mLayout.firstSample(c[1]) + ly);
                        const int64_t gz = mLayout.clampSample(2, mLayout.firstSample(c[2]) + lz);
                        const T v = volume[gx + dims[0] * (gy + dims[1] * gz)];
                        b[(size_t(lz) * side + ly) * side + lx] = v;
                        if (lx >= 1 && ly >= 1 && lz >= 1 &&
                            lx <= 1 + mLayout.cellsOnAxis(0, c[0]) &&
                            ly <= 1 + mLayout.cellsOnAxis(1, c[1]) &&
                            lz <= 1 + mLayout.cellsOnAxis(2, c[2])) {
                            lo = std::min(lo, double(v));
                            hi = std::max(hi, double(v));
                        }
                    }
            mRanges.push_back({float(lo), float(hi)});
            mSubBlocks.resize(mSubBlocks.size() + kSubBlocksPerBrick);
            measureSubBlocks(type, brick.data(), mLayout, c, mRanges.back(),
                             mSubBlocks.data() + mSubBlocks.size() - kSubBlocksPerBrick);
            mBricks.push_back(std::move(brick));
        }
    });
}

BrickHandle MemoryBrickSource::acquire(int64_t id) {
    ++mAcquired;
    ++mPinned;
    return BrickHandle(this, id, mBricks.at(size_t(id)).data());  // at(): a test asking for a brick that is not there fails
}

std::unique_ptr<MemoryBrickSource> synthBrickSource(const SynthParams& params, int brickSize) {
    std::vector<unsigned char> samples(VolumeInfo{params.dims, params.type}.byteSize());
    synthesizeSlices(params, 0, params.dims[2], samples.data());
    return visitScalarType(params.type, [&](auto zero) {
        using T = decltype(zero);
        const T* s = reinterpret_cast<const T*>(samples.data());
        return std::make_unique<MemoryBrickSource>(
            params.dims, params.type, brickSize, [&](int64_t x, int64_t y, int64_t z) {
                return double(s[x + params.dims[0] * (y + params.dims[1] * z)]);
            });
    });
}

double sphereDistance(const Dims3& dims, int64_t x, int64_t y, int64_t z) {
    const double cx = (dims[0] - 1) / 2.0, cy = (dims[1] - 1) / 2.0, cz = (dims[2] - 1) / 2.0;
    return std::sqrt((x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz));
}

namespace {

// Bit per face of the volume's box that the point lies on.
int boxFacesOf(const glm::vec3& p, const VolumeInfo& v) {
    int faces = 0;
    for (int a = 0; a < 3; ++a) {
        const double lo = v.origin[a], hi = v.origin[a] + double(v.dims[a] - 1) * v.spacing[a];
        if (std::abs(p[a] - lo) < 1e-4) faces |= 1 << (2 * a);
        if (std::abs(p[a] - hi) < 1e-4) faces |= 2 << (2 * a);
    }
    return faces;
}

}  // namespace

std::string checkClosedOriented(const TriangleMesh& mesh, const VolumeInfo* volume) {
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (size_t t = 0; t < mesh.triangleCount(); ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = mesh.indices[3 * t + k], b = mesh.indices[3 * t + (k + 1) % 3];
            if (a == b) return "degenerate triangle " + std::to_string(t);
            ++directed[{a, b}];
        }
    for (const auto& [edge, count] : directed) {
        if (count != 1)
            return "edge " + std::to_string(edge.first) + "-" + std::to_string(edge.second) +
                   " used " + std::to_string(count) + " times in one direction";
        auto opposite = directed.find({edge.second, edge.first});
        const bool onBorder =
            volume && (boxFacesOf(mesh.positions[edge.first], *volume) &
                       boxFacesOf(mesh.positions[edge.second], *volume)) != 0;
        if (opposite == directed.end() && !onBorder)
            return "edge " + std::to_string(edge.first) + "-" + std::to_string(edge.second) +
                   " has no opposite (a crack or a border)";
    }
    return "";
}

std::vector<std::array<float, 9>> canonicalTriangles(const TriangleMesh& mesh) {
    std::vector<std::array<float, 9>> out;
    auto round = [](float v) { return std::round(v * 1e4f) / 1e4f; };
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        std::array<glm::vec3, 3> v;
        for (int k = 0; k < 3; ++k) {
            const glm::vec3& p = mesh.positions[mesh.indices[3 * t + k]];
            v[size_t(k)] = glm::vec3(round(p.x), round(p.y), round(p.z));
        }
        // Rotate so the smallest vertex comes first; orientation is kept.
        auto less = [](const glm::vec3& a, const glm::vec3& b) {
            return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
        };
        const size_t first = size_t(std::min_element(v.begin(), v.end(), less) - v.begin());
        std::array<float, 9> key;
        for (size_t k = 0; k < 3; ++k) {
            const glm::vec3& p = v[(first + k) % 3];
            key[3 * k] = p.x;
            key[3 * k + 1] = p.y;
            key[3 * k + 2] = p.z;
        }
        out.push_back(key);
    }
    std::sort(out.begin(), out.end());
    return out;
}

double enclosedVolume(const TriangleMesh& mesh) {
    double volume = 0;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const glm::dvec3 a(mesh.positions[mesh.indices[3 * t]]);
        const glm::dvec3 b(mesh.positions[mesh.indices[3 * t + 1]]);
        const glm::dvec3 c(mesh.positions[mesh.indices[3 * t + 2]]);
        volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    return volume;
}

}  // namespace vdiso::test
