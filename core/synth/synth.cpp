#include "core/synth/synth.h"

#include <limits>
#include <stdexcept>
#include <string>

#include "core/synth/synth_models.h"

namespace vdiso {

double turbulenceIso(ScalarType type) {
    // Half-integers for the integer types, so no sample ever equals the isovalue.
    switch (type) {
        case ScalarType::U8:
            return 127.5;
        case ScalarType::I16:
            return 0.5;
        case ScalarType::U16:
            return 32767.5;
        case ScalarType::F32:
            return 0.0;
    }
    return 0.0;
}

void synthesizeSlices(const SynthParams& params, int64_t z0, int64_t count, void* dst) {
    const Dims3& d = params.dims;
    if (d[0] < 2 || d[1] < 2 || d[2] < 2 || d[0] > std::numeric_limits<int>::max() / 2)
        throw std::invalid_argument("synth: dimensions must be between 2 and 2^30");
    if (const std::string problem = volumeDimsProblem(d); !problem.empty())
        throw std::invalid_argument("synth: " + problem);
    if (z0 < 0 || count < 0 || z0 + count > d[2])
        throw std::invalid_argument("synth: slices [" + std::to_string(z0) + ", " +
                                    std::to_string(z0 + count) + ") outside the volume's " +
                                    std::to_string(d[2]));
    if (params.kind == SynthKind::Head)
        synth_detail::synthesizeHead(params, z0, count, dst);
    else
        synth_detail::synthesizeTurbulence(params, z0, count, dst);
}

}  // namespace vdiso
