#include "array_slices.h"

#include <pybind11/numpy.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "arrays.h"
#include "core/interrupt.h"
#include "io/error.h"

namespace vdiso::py {

namespace pyb = pybind11;
using namespace pybind11::literals;

ArraySlices::ArraySlices(const pyb::object& source, const VolumeInfo& info, FileScalar type, std::string name,
                         std::vector<int64_t> bounds)
    : mInfo(info), mType(type), mName(std::move(name)), mBounds(std::move(bounds)) {
    {  // made on a thread that may not hold the GIL (inside runReleased): a reference is
       // Python's to count
        pyb::gil_scoped_acquire acquire;
        mSource = source;
    }
    const size_t sliceBytes = size_t(info.sliceSamples()) * scalarSize(info.type);
    for (size_t k = 0; k + 1 < mBounds.size(); ++k)
        if (size_t(mBounds[k + 1] - mBounds[k]) * sliceBytes > kSlabBytes) mBounds.clear();
}

ArraySlices::~ArraySlices() {
    pyb::gil_scoped_acquire acquire;
    mSource = pyb::object();
}

void ArraySlices::read(void* dst, int64_t count) {
    if (mBounds.empty()) {
        readSource(dst, mNext, count);
        mNext += count;
        return;
    }
    auto* out = static_cast<unsigned char*>(dst);
    const size_t sliceBytes = size_t(mInfo.sliceSamples()) * scalarSize(mInfo.type);
    for (int64_t s = 0; s < count;) {
        const int64_t z = mNext + s;
        if (z < mSlabFirst || z >= mSlabEnd) loadSlab(z);
        const int64_t n = std::min(count - s, mSlabEnd - z);
        std::memcpy(out + size_t(s) * sliceBytes, mSlab.data() + size_t(z - mSlabFirst) * sliceBytes,
                    size_t(n) * sliceBytes);
        s += n;
    }
    mNext += count;
}

// The chunk holding slice z, whole, into mSlab.
void ArraySlices::loadSlab(int64_t z) {
    const auto after = std::upper_bound(mBounds.begin(), mBounds.end(), z);
    if (after == mBounds.begin() || after == mBounds.end())
        throwIoError(mName, "has no chunk holding slice " + std::to_string(z));
    mSlabFirst = *(after - 1);
    mSlabEnd = *after;
    mSlab.resize(size_t(mSlabEnd - mSlabFirst) * size_t(mInfo.sliceSamples()) * scalarSize(mInfo.type));
    readSource(mSlab.data(), mSlabFirst, mSlabEnd - mSlabFirst);
}

// Slices [z, z + count) of the source into dst, in the store's type.
void ArraySlices::readSource(void* dst, int64_t z, int64_t count) {
    // A slab of a Dask array may be seconds of computing that nothing can interrupt: an
    // interrupt asked for meanwhile stops the reader before the next one.
    throwIfInterrupted(mName);
    pyb::gil_scoped_acquire acquire;
    const pyb::module_ np = pyb::module_::import("numpy");
    pyb::object got = mSource[pyb::slice(pyb::int_(z), pyb::int_(z + count), pyb::none())];
    const std::string range = "slices " + std::to_string(z) + " to " + std::to_string(z + count);
    // A Dask slab of the store's own type is computed chunk by chunk into an array of its own
    // (Dask's store()), then copied: the slab is never concatenated in memory first. The array is
    // Python's, not dst: when one chunk fails, store() raises while other chunks may still be
    // running, and they must not write into memory the unwinding frees.
    if (fileScalarOf(mInfo.type) == mType && pyb::hasattr(got, "store") && pyb::hasattr(got, "dask")) {
        checkShape(pyb::tuple(got.attr("shape")), count, range);
        const pyb::array target(dtypeOf(mInfo.type), std::vector<pyb::ssize_t>{count, mInfo.dims[1], mInfo.dims[0]});
        got.attr("store")(target, "lock"_a = false);
        std::memcpy(dst, target.data(), size_t(target.nbytes()));
        return;
    }
    const pyb::array slab = np.attr("ascontiguousarray")(np.attr("asarray")(got));
    checkShape(pyb::tuple(slab.attr("shape")), count, range);
    if (fileScalarOfDtype(slab.dtype(), mName.c_str()) != mType)
        throwIoError(mName, range + " came back as " + pyb::str(pyb::handle(slab.dtype())).cast<std::string>() +
                                ", not the array's dtype");
    decodeSamples(slab.data(), mType, false, size_t(slab.size()), dst, mInfo.type);
}

void ArraySlices::checkShape(const pyb::tuple& shape, int64_t count, const std::string& range) const {
    if (shape.size() != 3 || shape[0].cast<int64_t>() != count || shape[1].cast<int64_t>() != mInfo.dims[1] ||
        shape[2].cast<int64_t>() != mInfo.dims[0])
        throwIoError(mName, range + " came back with shape " + pyb::str(pyb::handle(shape)).cast<std::string>() +
                                ", not (" + std::to_string(count) + ", " + std::to_string(mInfo.dims[1]) + ", " +
                                std::to_string(mInfo.dims[0]) + ")");
}

VolumeInfo arrayVolumeInfo(const std::string& name, const std::vector<int64_t>& shape, FileScalar type,
                           std::array<double, 3> spacing, std::array<double, 3> origin) {
    if (shape.size() != 3)
        throw std::invalid_argument(name + ": expects a 3-D array, not one of " + std::to_string(shape.size()) +
                                    " dimensions");
    VolumeInfo info;
    info.dims = {shape[2], shape[1], shape[0]};
    if (const std::string problem = volumeDimsProblem(info.dims); !problem.empty())
        throw std::invalid_argument(name + ": " + problem);
    info.type = storeTypeFor(type, false);
    for (int a = 0; a < 3; ++a) {
        if (!(spacing[size_t(a)] > 0 && std::isfinite(spacing[size_t(a)])))
            throw std::invalid_argument("spacing: expects three positive finite numbers");
        if (!std::isfinite(origin[size_t(a)])) throw std::invalid_argument("origin: expects three finite numbers");
    }
    info.spacing = glm::dvec3(spacing[2], spacing[1], spacing[0]);
    info.origin = glm::dvec3(origin[0], origin[1], origin[2]);  // world x, y, z
    return info;
}

void checkChunkBounds(const std::string& name, const std::vector<int64_t>& shape, const std::vector<int64_t>& bounds) {
    bool ordered = bounds.empty() || (bounds.front() == 0 && bounds.back() == shape[0]);
    for (size_t k = 1; ordered && k < bounds.size(); ++k) ordered = bounds[k] > bounds[k - 1];
    if (!ordered) throw std::invalid_argument(name + ": chunks along axis 0 that do not add up to its shape");
}

}  // namespace vdiso::py
