// vdiso.convert: a file (any format vdiso convert reads) or an array-like (NumPy, Zarr, Dask, or
// anything with shape, dtype and slicing along axis 0) into a brick store, slab by slab.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cstring>
#include <optional>
#include <stdexcept>

#include "arrays.h"
#include "bindings.h"
#include "core/settings_error.h"
#include "io/error.h"
#include "io/readers/slice_reader.h"
#include "io/store/store_writer.h"
#include "io/store/zarr_index.h"
#include "io/readers/volume_open.h"
#include "released.h"

namespace vdiso::py {

namespace pyb = pybind11;
using namespace pybind11::literals;

namespace {

// The slices of an array-like, z = NumPy's axis 0: each read takes the GIL, slices the object
// and checks what comes back before converting it to the store type.
class ArraySlices final : public SliceReader {
public:
    // `bounds`: where the source's chunks begin along axis 0, and its end (empty: not chunked).
    // Then whole chunks' slabs are read, so that a chunk is computed or decoded once however the
    // writer's reads cut it, unless a chunk's slab would exceed kSlabBytes (then reads go
    // through as asked, the writer's bounded memory first).
    ArraySlices(pyb::object source, const VolumeInfo& info, FileScalar type, std::string name,
                std::vector<int64_t> bounds)
        : mSource(std::move(source)), mInfo(info), mType(type), mName(std::move(name)), mBounds(std::move(bounds)) {
        const size_t sliceBytes = size_t(info.sliceSamples()) * scalarSize(info.type);
        for (size_t k = 0; k + 1 < mBounds.size(); ++k)
            if (size_t(mBounds[k + 1] - mBounds[k]) * sliceBytes > kSlabBytes) mBounds.clear();
    }
    static constexpr size_t kSlabBytes = size_t(512) << 20;
    ~ArraySlices() override {
        pyb::gil_scoped_acquire acquire;
        mSource = pyb::object();
    }
    const VolumeInfo& info() const override { return mInfo; }
    std::string name() const override { return mName; }

    void read(void* dst, int64_t count) override {
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

private:
    // The chunk holding slice z, whole, into mSlab.
    void loadSlab(int64_t z) {
        const auto after = std::upper_bound(mBounds.begin(), mBounds.end(), z);
        if (after == mBounds.begin() || after == mBounds.end())
            throwIoError(mName, "has no chunk holding slice " + std::to_string(z));
        mSlabFirst = *(after - 1);
        mSlabEnd = *after;
        mSlab.resize(size_t(mSlabEnd - mSlabFirst) * size_t(mInfo.sliceSamples()) * scalarSize(mInfo.type));
        readSource(mSlab.data(), mSlabFirst, mSlabEnd - mSlabFirst);
    }

    // Slices [z, z + count) of the source into dst, in the store's type.
    void readSource(void* dst, int64_t z, int64_t count) {
        pyb::gil_scoped_acquire acquire;
        const pyb::module_ np = pyb::module_::import("numpy");
        pyb::object got = mSource[pyb::slice(pyb::int_(z), pyb::int_(z + count), pyb::none())];
        const std::string range = "slices " + std::to_string(z) + " to " + std::to_string(z + count);
        // A Dask slab of the store's own type is computed chunk by chunk into the destination
        // (Dask's store()): the slab is never concatenated in memory first.
        if (fileScalarOf(mInfo.type) == mType && pyb::hasattr(got, "store") && pyb::hasattr(got, "dask")) {
            checkShape(pyb::tuple(got.attr("shape")), count, range);
            const pyb::array target(dtypeOf(mInfo.type), std::vector<pyb::ssize_t>{count, mInfo.dims[1], mInfo.dims[0]},
                                    dst, pyb::capsule(dst, [](void*) {}));
            got.attr("store")(target, "lock"_a = false);
            return;
        }
        const pyb::array slab = np.attr("ascontiguousarray")(np.attr("asarray")(got));
        checkShape(pyb::tuple(slab.attr("shape")), count, range);
        if (fileScalarOfDtype(slab.dtype(), mName.c_str()) != mType)
            throwIoError(mName, range + " came back as " + pyb::str(pyb::handle(slab.dtype())).cast<std::string>() +
                                    ", not the array's dtype");
        decodeSamples(slab.data(), mType, false, size_t(slab.size()), dst, mInfo.type);
    }

    void checkShape(const pyb::tuple& shape, int64_t count, const std::string& range) const {
        if (shape.size() != 3 || shape[0].cast<int64_t>() != count || shape[1].cast<int64_t>() != mInfo.dims[1] ||
            shape[2].cast<int64_t>() != mInfo.dims[0])
            throwIoError(mName, range + " came back with shape " + pyb::str(pyb::handle(shape)).cast<std::string>() + ", not (" +
                                    std::to_string(count) + ", " + std::to_string(mInfo.dims[1]) + ", " +
                                    std::to_string(mInfo.dims[0]) + ")");
    }

    pyb::object mSource;
    VolumeInfo mInfo;
    FileScalar mType;
    std::string mName;
    std::vector<int64_t> mBounds;
    std::vector<unsigned char> mSlab;  // slices [mSlabFirst, mSlabEnd): one chunk's
    int64_t mSlabFirst = 0, mSlabEnd = 0;
    int64_t mNext = 0;
};

StoreWriteOptions storeOptions(int64_t brick, const std::string& levels, const std::string& compress, bool overwrite) {
    StoreWriteOptions o;
    o.brickSize = int(checkedInt("brick", brick, 2, 512));
    o.overwrite = overwrite;
    const std::optional<Compression> codec = parseCompression(compress);
    if (!codec) throw SettingsError("compress", "expects 'lz4', 'zstd' or 'none', not '" + compress + "'");
    o.compression = *codec;
    if (levels == "auto") o.coarseLevels = StoreWriteOptions::kLevelsUntilOneBrick;
    else {
        try {
            size_t end = 0;
            o.coarseLevels = std::stoi(levels, &end);
            if (end != levels.size() || o.coarseLevels < 0) throw std::invalid_argument("");
        } catch (const std::exception&) {
            throw SettingsError("levels", "expects 'auto' or a count of coarser levels (0 or more), not '" + levels + "'");
        }
    }
    return o;
}

pyb::dict summaryOf(const StoreWriteSummary& s) {
    return pyb::dict("bricks"_a = s.bricks, "levels"_a = s.levels, "level0_bytes"_a = s.level0Bytes,
                     "coarse_bytes"_a = s.coarseBytes, "input_bytes"_a = s.inputBytes, "file_bytes"_a = s.fileBytes,
                     "seconds"_a = s.seconds);
}

pyb::dict convertFiles(const std::vector<std::string>& inputs, const std::string& output,
                       std::optional<std::array<double, 3>> spacing, int64_t brick, const std::string& levels,
                       const std::string& compress, bool overwrite, pyb::object progress) {
    InputOptions input;
    // NumPy's axis order (z, y, x), as marching_cubes takes it.
    if (spacing) input.spacing = glm::dvec3((*spacing)[2], (*spacing)[1], (*spacing)[0]);
    const StoreWriteOptions options = storeOptions(brick, levels, compress, overwrite);
    StoreWriteSummary summary;
    std::unique_ptr<SliceReader> source;
    {
        pyb::gil_scoped_release release;
        source = openVolume(inputs, input);
    }
    runReleased([&](const ProgressFn& fraction) { summary = writeBrickStore(*source, output, options, fraction); },
                progress, double(source->info().byteSize()));
    return summaryOf(summary);
}

pyb::dict convertArray(pyb::object source, const std::string& name, const std::vector<int64_t>& shape,
                       const pyb::dtype& dtype, const std::string& output, std::array<double, 3> spacing,
                       std::array<double, 3> origin, int64_t brick, const std::string& levels,
                       const std::string& compress, bool overwrite, std::vector<int64_t> bounds,
                       pyb::object progress) {
    if (shape.size() != 3)
        throw std::invalid_argument(name + ": expects a 3-D array, not one of " + std::to_string(shape.size()) +
                                    " dimensions");
    const FileScalar type = fileScalarOfDtype(dtype, name.c_str());
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
    const StoreWriteOptions options = storeOptions(brick, levels, compress, overwrite);
    bool ordered = bounds.empty() || (bounds.front() == 0 && bounds.back() == shape[0]);
    for (size_t k = 1; ordered && k < bounds.size(); ++k) ordered = bounds[k] > bounds[k - 1];
    if (!ordered) throw std::invalid_argument(name + ": chunks along axis 0 that do not add up to its shape");
    ArraySlices slices(std::move(source), info, type, name, std::move(bounds));
    StoreWriteSummary summary;
    runReleased([&](const ProgressFn& fraction) { summary = writeBrickStore(slices, output, options, fraction); },
                progress, double(info.byteSize()));
    return summaryOf(summary);
}

// vdiso.index: the Zarr array at `data` indexed where it lies (vdiso index).
pyb::dict indexData(const std::string& data, const std::string& index, int64_t level, int64_t brick,
                    const std::string& levels, bool overwrite, bool restart, double checkpointSeconds,
                    pyb::object progress) {
    ZarrIndexOptions options;
    options.level = int(checkedInt("scale_level", level, 0, 64));
    options.restart = restart;
    if (!(checkpointSeconds >= 0)) throw std::invalid_argument("checkpoint_seconds: expects seconds, 0 or more");
    options.checkpointSeconds = checkpointSeconds;
    options.store = storeOptions(brick, levels, "lz4", overwrite);
    const std::string out = indexPathFor(data, index);
    ZarrIndexSummary summary;
    runReleased([&](const ProgressFn& fraction) { summary = indexZarr(data, out, options, fraction); }, progress, 0.0);
    pyb::dict d = summaryOf(summary.store);
    d["index"] = out;
    d["chunks"] = summary.chunks;
    d["missing_chunks"] = summary.missingChunks;
    d["data_bytes"] = summary.dataBytes;
    d["resumed_layers"] = summary.store.resumedLayers;
    d["layers"] = summary.store.layers;
    return d;
}

}  // namespace

void bindConvert(pyb::module_& m) {
    m.def("_index", &indexData, "data"_a, "index"_a, "level"_a, "brick"_a, "levels"_a, "overwrite"_a, "restart"_a,
          "checkpoint_seconds"_a, "progress"_a);
    m.def("_convert_files", &convertFiles, "inputs"_a, "output"_a, "spacing"_a, "brick"_a, "levels"_a, "compress"_a,
          "overwrite"_a, "progress"_a);
    m.def("_convert_array", &convertArray, "source"_a, "name"_a, "shape"_a, "dtype"_a, "output"_a, "spacing"_a,
          "origin"_a, "brick"_a, "levels"_a, "compress"_a, "overwrite"_a, "bounds"_a, "progress"_a);
}

}  // namespace vdiso::py
