// vdiso.convert: a file (any format vdiso convert reads) or an array-like (NumPy, Zarr, Dask, or
// anything with shape, dtype and slicing along axis 0) into a brick store, slab by slab.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cstring>
#include <optional>
#include <stdexcept>

#include "array_slices.h"
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
    const FileScalar type = fileScalarOfDtype(dtype, name.c_str());
    const VolumeInfo info = arrayVolumeInfo(name, shape, type, spacing, origin);
    const StoreWriteOptions options = storeOptions(brick, levels, compress, overwrite);
    checkChunkBounds(name, shape, bounds);
    ArraySlices slices(std::move(source), info, type, name, std::move(bounds));
    StoreWriteSummary summary;
    runReleased([&](const ProgressFn& fraction) { summary = writeBrickStore(slices, output, options, fraction); },
                progress, double(info.byteSize()));
    return summaryOf(summary);
}

// vdiso.index: the Zarr array at `data` indexed where it lies (vdiso index).
pyb::dict indexData(const std::string& data, const std::string& index, int64_t level, int64_t brick,
                    const std::string& levels, int64_t scaleLevels, bool overwrite, bool restart,
                    double checkpointSeconds, pyb::object progress) {
    ZarrIndexOptions options;
    options.scaleLevels = int(checkedInt("scale_levels", scaleLevels, 0, 16));
    options.level = int(checkedInt("scale_level", level, 0, 64));
    options.restart = restart;
    if (!(checkpointSeconds >= 0)) throw std::invalid_argument("checkpoint_seconds: expects seconds, 0 or more");
    options.checkpointSeconds = checkpointSeconds;
    options.store = storeOptions(brick, levels, "lz4", overwrite);
    const std::string out = indexPathFor(data, index);
    ZarrIndexSummary summary;
    runReleased([&](const ProgressFn& fraction) { summary = indexZarr(data, out, options, fraction); }, progress, 1.0);
    pyb::dict d = summaryOf(summary.store);
    d["index"] = out;
    d["chunks"] = summary.chunks;
    d["missing_chunks"] = summary.missingChunks;
    d["data_bytes"] = summary.dataBytes;
    d["resumed_layers"] = summary.store.resumedLayers;
    d["layers"] = summary.store.layers;
    d["own_scale_levels"] = summary.ownScaleLevels;
    d["scales_not_used"] = summary.scalesNotUsed;
    return d;
}

}  // namespace

void bindConvert(pyb::module_& m) {
    m.def("_index", &indexData, "data"_a, "index"_a, "level"_a, "brick"_a, "levels"_a, "scale_levels"_a, "overwrite"_a,
          "restart"_a, "checkpoint_seconds"_a, "progress"_a);
    m.def("_convert_files", &convertFiles, "inputs"_a, "output"_a, "spacing"_a, "brick"_a, "levels"_a, "compress"_a,
          "overwrite"_a, "progress"_a);
    m.def("_convert_array", &convertArray, "source"_a, "name"_a, "shape"_a, "dtype"_a, "output"_a, "spacing"_a,
          "origin"_a, "brick"_a, "levels"_a, "compress"_a, "overwrite"_a, "bounds"_a, "progress"_a);
}

}  // namespace vdiso::py
