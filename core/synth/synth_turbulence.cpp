// Generated turbulence (core/synth/synth.h): a fractal sum of gradient noise, filled a row at a time.
#include "core/synth/synth_models.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <glm/vec3.hpp>

#include "core/synth/synth_noise.h"
#include "core/synth/synth_rows.h"

namespace vdiso::synth_detail {
namespace {


constexpr int kMaxOctaves = 6;
constexpr double kBaseCells = 6.0;      // lattice cells across the smallest dimension
constexpr double kMinCellVoxels = 2.0;  // finer octaves would only alias into white noise
// |noise sum| rarely exceeds this; values are scaled so that it maps to the type's range.
constexpr float kTurbulenceBound = 0.8f;

inline float fade(float t) {
    return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f);
}

// A gradient drawn uniformly from the cube [-1, 1]^3: 21 bits per component.
inline glm::vec3 gradient(uint64_t h) {
    constexpr float kScale = 2.0f / float(1 << 21);
    const auto component = [&](int shift) {
        return float((h >> shift) & ((1u << 21) - 1)) * kScale - 1.0f;
    };
    return {component(0), component(21), component(42)};
}

class TurbulenceModel {
    struct Octave;

public:
    // Per-task state: each octave's gradients along the four lattice lines around the current
    // row, kept while consecutive rows stay between the same lines, and the columns' sums.
    struct Scratch {
        struct Lines {
            int64_t iy = std::numeric_limits<int64_t>::min(), iz = 0;
            std::vector<float> gx[4], gy[4], gz[4];
        };
        std::vector<Lines> lines;
        std::vector<float> slopes, offsets;
        explicit Scratch(const TurbulenceModel& m) : lines(m.mOctaves.size()) {
            size_t most = 0;
            for (const Octave& o : m.mOctaves) most = std::max(most, size_t(o.columns));
            slopes.resize(most);
            offsets.resize(most);
        }
    };

    TurbulenceModel(const SynthParams& p, float center, float scale)
        : mNx(int(p.dims[0])), mCenter(center), mScale(scale) {
        const int64_t smallest = std::min({p.dims[0], p.dims[1], p.dims[2]});
        double cellsPerVoxel = kBaseCells / double(smallest);
        float amplitude = 1.0f;
        for (int o = 0; o < kMaxOctaves; ++o) {
            if (o > 0 && 1.0 / cellsPerVoxel < kMinCellVoxels) break;
            mOctaves.push_back(makeOctave(p.seed, o, cellsPerVoxel, amplitude));
            cellsPerVoxel *= 2.0;
            amplitude *= 0.5f;
        }
    }

    void fillRow(int64_t y, int64_t z, Scratch& s, float* out) const {
        std::fill(out, out + mNx, 0.0f);
        for (size_t o = 0; o < mOctaves.size(); ++o) addOctave(mOctaves[o], y, z, s, o, out);
        for (int x = 0; x < mNx; ++x) out[x] = mCenter + mScale * out[x];
    }

private:
    struct Octave {
        double cellsPerVoxel = 1.0;
        double offset[3] = {0.0, 0.0, 0.0};
        uint64_t key = 0;
        float amplitude = 1.0f;
        // Where each x falls in the lattice is the same for every row: the fraction across its
        // cell, that fraction faded, and the run of samples each column's cell covers.
        int64_t firstColumn = 0, columns = 0;
        std::vector<int> runStart;  // columns + 1 entries; the last column starts no cell
        std::vector<float> fraction, faded;
    };

    Octave makeOctave(uint64_t seed, int index, double cellsPerVoxel, float amplitude) const {
        Octave o;
        o.cellsPerVoxel = cellsPerVoxel;
        o.key = mix64(seed + uint64_t(index + 1) * kGolden64);
        // Offsets keep the octaves' lattices (where each octave is zero) from lining up.
        for (int a = 0; a < 3; ++a)
            o.offset[a] = double(mix64(o.key + uint64_t(a)) >> 11) * 0x1.0p-53;
        o.amplitude = amplitude;
        // Positions are never negative, so truncation is floor.
        o.firstColumn = int64_t(o.offset[0]);
        o.columns = int64_t(double(mNx - 1) * cellsPerVoxel + o.offset[0]) + 2 - o.firstColumn;
        o.runStart.assign(size_t(o.columns + 1), mNx);
        for (int x = mNx - 1; x >= 0; --x) {
            const double px = double(x) * cellsPerVoxel + o.offset[0];
            const int64_t ix = int64_t(px);
            o.runStart[size_t(ix - o.firstColumn)] = x;
            o.fraction.push_back(float(px - double(ix)));
        }
        std::reverse(o.fraction.begin(), o.fraction.end());
        // Columns no sample falls in start where the next one does.
        for (int64_t c = o.columns - 1; c >= 0; --c)
            o.runStart[size_t(c)] = std::min(o.runStart[size_t(c)], o.runStart[size_t(c + 1)]);
        for (float f : o.fraction) o.faded.push_back(fade(f));
        return o;
    }

    void loadLines(const Octave& o, int64_t iy, int64_t iz, Scratch::Lines& lines) const {
        if (lines.iy == iy && lines.iz == iz && !lines.gx[0].empty()) return;
        lines.iy = iy;
        lines.iz = iz;
        for (int k = 0; k < 4; ++k) {
            const uint64_t key = latticeKey(o.key, iy + (k & 1), iz + (k >> 1));
            lines.gx[k].resize(size_t(o.columns));
            lines.gy[k].resize(size_t(o.columns));
            lines.gz[k].resize(size_t(o.columns));
            for (int64_t c = 0; c < o.columns; ++c) {
                const glm::vec3 g = gradient(latticeHash(key, o.firstColumn + c));
                lines.gx[k][size_t(c)] = g.x;
                lines.gy[k][size_t(c)] = g.y;
                lines.gz[k][size_t(c)] = g.z;
            }
        }
    }

    // Along a row, y and z are fixed, so each lattice column's four corners collapse (after the
    // y-z interpolation) to one linear function of x: slope * fx + offset. Across a cell the
    // noise is then a lerp of two such lines, with constants for the whole run of samples.
    void addOctave(const Octave& o, int64_t y, int64_t z, Scratch& s, size_t index,
                   float* out) const {
        const double py = double(y) * o.cellsPerVoxel + o.offset[1];
        const double pz = double(z) * o.cellsPerVoxel + o.offset[2];
        const int64_t iy = int64_t(py), iz = int64_t(pz);
        const float fy = float(py - double(iy)), fz = float(pz - double(iz));
        const float wy = fade(fy), wz = fade(fz);
        Scratch::Lines& lines = s.lines[index];
        loadLines(o, iy, iz, lines);

        // The octave's amplitude rides along in the corner weights.
        float toSlope[4], toOffsetY[4], toOffsetZ[4];
        for (int k = 0; k < 4; ++k) {
            const int a = k & 1, b = k >> 1;
            const float w = o.amplitude * (a ? wy : 1.0f - wy) * (b ? wz : 1.0f - wz);
            toSlope[k] = w;
            toOffsetY[k] = w * (fy - float(a));
            toOffsetZ[k] = w * (fz - float(b));
        }
        float* slopes = s.slopes.data();
        float* offsets = s.offsets.data();
        for (int64_t c = 0; c < o.columns; ++c) {
            float slope = 0.0f, offset = 0.0f;
            for (int k = 0; k < 4; ++k) {
                slope += toSlope[k] * lines.gx[k][size_t(c)];
                offset +=
                    toOffsetY[k] * lines.gy[k][size_t(c)] + toOffsetZ[k] * lines.gz[k][size_t(c)];
            }
            slopes[c] = slope;
            offsets[c] = offset;
        }
        const float* fraction = o.fraction.data();
        const float* faded = o.faded.data();
        for (int64_t c = 0; c + 1 < o.columns; ++c) {
            const float s0 = slopes[c], o0 = offsets[c];
            const float s1 = slopes[c + 1], o1 = offsets[c + 1] - s1;
            for (int x = o.runStart[size_t(c)]; x < o.runStart[size_t(c + 1)]; ++x) {
                const float n0 = s0 * fraction[x] + o0;
                const float n1 = s1 * fraction[x] + o1;
                out[x] += n0 + (n1 - n0) * faded[x];
            }
        }
    }

    int mNx;
    float mCenter, mScale;
    std::vector<Octave> mOctaves;
};

// Half the distance from the centre to the nearer end of the type's range.
float turbulenceHalfRange(ScalarType type) {
    switch (type) {
        case ScalarType::U8:
            return 127.0f;
        case ScalarType::I16:
            return 32767.0f;
        case ScalarType::U16:
            return 32767.0f;
        case ScalarType::F32:
            return 1.0f;
    }
    return 1.0f;
}

}  // namespace

void synthesizeTurbulence(const SynthParams& params, int64_t z0, int64_t count, void* dst) {
    const float scale = turbulenceHalfRange(params.type) / kTurbulenceBound;
    visitScalarType(params.type, [&](auto zero) {
        using T = decltype(zero);
        generate(TurbulenceModel(params, float(turbulenceIso(params.type)), scale), params.dims, z0, count,
                 static_cast<T*>(dst));
    });
}

}  // namespace vdiso::synth_detail
