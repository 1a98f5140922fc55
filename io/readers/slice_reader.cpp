#include "io/readers/slice_reader.h"

#include <algorithm>
#include <stdexcept>

namespace vdiso {

void SliceReader::skip(int64_t count) {
    if (count < 0) throw std::invalid_argument(name() + ": cannot skip a negative count of slices");
    const size_t sliceBytes = size_t(info().sliceSamples()) * scalarSize(info().type);
    const int64_t perRead = std::max<int64_t>(1, int64_t((size_t(16) << 20) / std::max<size_t>(sliceBytes, 1)));
    std::vector<unsigned char> scratch(size_t(std::min(count, perRead)) * sliceBytes);
    while (count > 0) {
        const int64_t n = std::min(count, perRead);
        read(scratch.data(), n);
        count -= n;
    }
}

}  // namespace vdiso
