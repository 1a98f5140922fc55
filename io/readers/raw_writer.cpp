#include "io/readers/raw_writer.h"

#include <algorithm>
#include <vector>

#include "io/atomic_output.h"

namespace vdiso {

uint64_t writeRawVolume(SliceReader& source, const std::string& outPath, bool overwrite,
                        const ProgressFn& progress) {
    const VolumeInfo info = source.info();
    const size_t sliceBytes = size_t(info.sliceSamples()) * scalarSize(info.type);
    // About 64 MiB a slab: large writes, bounded memory whatever the volume's depth.
    const int64_t slab = std::max<int64_t>(1, int64_t((64u << 20) / sliceBytes));
    std::vector<unsigned char> buffer(size_t(std::min(slab, info.dims[2])) * sliceBytes);
    AtomicOutputFile out(outPath, overwrite);
    for (int64_t z = 0; z < info.dims[2]; z += slab) {
        const int64_t count = std::min(slab, info.dims[2] - z);
        source.read(buffer.data(), count);
        out.append(buffer.data(), size_t(count) * sliceBytes);
        if (progress) progress(double(z + count) / double(info.dims[2]));
    }
    source.finish();
    out.commit();
    return out.size();
}

}  // namespace vdiso
