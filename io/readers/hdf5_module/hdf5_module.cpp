// The HDF5 module (see hdf5_module.h): libhdf5's part of io/readers/hdf5_reader.h, whose header says
// what is read and how; the rest (store types, conversion, the helper process) is vdiso's.
#include "io/readers/hdf5_module/hdf5_module.h"

#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/volume.h"
#include "io/readers/sample_decode.h"

namespace vdiso {
namespace {

// Why a file cannot be read, whole ("FILE:/dataset: ..."): becomes the host's IoError.
struct Failure : std::runtime_error {
    using std::runtime_error::runtime_error;
};

[[noreturn]] void fail(const std::string& where, const std::string& message) {
    throw Failure(where + ": " + message);
}

// HDF5 prints its error stack to stderr by default; ours are exceptions.
void silenceHdf5() {
    static const bool silenced = [] {
        H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
        return true;
    }();
    (void)silenced;
}

// The innermost message on HDF5's error stack (then cleared): the one that says what failed.
std::string hdf5Message() {
    std::string message;
    H5Ewalk2(
        H5E_DEFAULT, H5E_WALK_UPWARD,
        [](unsigned n, const H5E_error2_t* e, void* data) -> herr_t {
            if (n == 0 && e && e->desc) *static_cast<std::string*>(data) = e->desc;
            return 0;
        },
        &message);
    H5Eclear2(H5E_DEFAULT);
    return message;
}

// Owns an HDF5 identifier, closed with `close`.
class Handle {
public:
    Handle(hid_t id, herr_t (*close)(hid_t)) : mId(id), mClose(close) {}
    ~Handle() {
        if (mId >= 0) mClose(mId);
    }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    Handle(Handle&& o) noexcept : mId(o.mId), mClose(o.mClose) { o.mId = -1; }
    Handle& operator=(Handle&& o) noexcept {
        if (this != &o) {
            if (mId >= 0) mClose(mId);
            mId = o.mId;
            mClose = o.mClose;
            o.mId = -1;
        }
        return *this;
    }
    hid_t get() const { return mId; }
    bool valid() const { return mId >= 0; }

private:
    hid_t mId;
    herr_t (*mClose)(hid_t);
};

std::optional<FileScalar> sampleType(hid_t type) {
    const H5T_class_t cls = H5Tget_class(type);
    const size_t size = H5Tget_size(type);
    if (cls == H5T_INTEGER) {
        const bool isSigned = H5Tget_sign(type) == H5T_SGN_2;
        switch (size) {
            case 1: return isSigned ? FileScalar::I8 : FileScalar::U8;
            case 2: return isSigned ? FileScalar::I16 : FileScalar::U16;
            case 4: return isSigned ? FileScalar::I32 : FileScalar::U32;
        }
    } else if (cls == H5T_FLOAT) {
        if (size == 4) return FileScalar::F32;
        if (size == 8) return FileScalar::F64;
    }
    return std::nullopt;
}

hid_t nativeType(FileScalar t) {
    switch (t) {
        case FileScalar::I8: return H5T_NATIVE_INT8;
        case FileScalar::U8: return H5T_NATIVE_UINT8;
        case FileScalar::I16: return H5T_NATIVE_INT16;
        case FileScalar::U16: return H5T_NATIVE_UINT16;
        case FileScalar::I32: return H5T_NATIVE_INT32;
        case FileScalar::U32: return H5T_NATIVE_UINT32;
        case FileScalar::F32: return H5T_NATIVE_FLOAT;
        case FileScalar::F64: break;
    }
    return H5T_NATIVE_DOUBLE;
}

const char* className(H5T_class_t c) {
    switch (c) {
        case H5T_INTEGER: return "integer";
        case H5T_FLOAT: return "floating-point";
        case H5T_STRING: return "string";
        case H5T_COMPOUND: return "compound";
        case H5T_ENUM: return "enum";
        case H5T_ARRAY: return "array";
        case H5T_VLEN: return "variable-length";
        case H5T_REFERENCE: return "reference";
        case H5T_OPAQUE: return "opaque";
        case H5T_BITFIELD: return "bitfield";
        default: return "unknown";
    }
}

// "3-D u16 of 512 x 512 x 100" for messages, or why it is not a volume.
struct DatasetShape {
    int rank = 0;
    hsize_t dims[3] = {0, 0, 0};
    std::optional<FileScalar> type;
    std::string problem;  // "" when it is a 3-D numeric dataset
};

DatasetShape shapeOf(hid_t dataset) {
    DatasetShape s;
    Handle space(H5Dget_space(dataset), H5Sclose);
    Handle type(H5Dget_type(dataset), H5Tclose);
    if (!space.valid() || !type.valid()) {
        s.problem = "cannot be described: " + hdf5Message();
        return s;
    }
    s.rank = H5Sget_simple_extent_ndims(space.get());
    if (s.rank == 3) H5Sget_simple_extent_dims(space.get(), s.dims, nullptr);
    s.type = sampleType(type.get());
    if (s.rank != 3)
        s.problem = "is " + std::to_string(std::max(s.rank, 0)) +
                    "-D: a 3-D dataset (z, y, x) is needed";
    else if (!s.type)
        s.problem = "holds " + std::to_string(H5Tget_size(type.get())) + "-byte " +
                    className(H5Tget_class(type.get())) +
                    " data: 8, 16 or 32-bit integers or 32/64-bit floats are needed";
    return s;
}

// Every 3-D numeric dataset in the file (for the file alone), and the other datasets, by path.
struct DatasetSearch {
    hid_t file;
    std::vector<std::string> volumes, others;
};

herr_t visitLink(hid_t group, const char* name, const H5L_info_t* info, void* data) {
    auto* search = static_cast<DatasetSearch*>(data);
    if (info->type != H5L_TYPE_HARD) return 0;
    Handle dataset(H5Dopen2(group, name, H5P_DEFAULT), H5Dclose);
    if (!dataset.valid()) {
        H5Eclear2(H5E_DEFAULT);
        return 0;  // a group, or a named type
    }
    const std::string path = std::string("/") + name;
    (shapeOf(dataset.get()).problem.empty() ? search->volumes : search->others).push_back(path);
    return search->volumes.size() + search->others.size() > 10000 ? 1 : 0;
}

std::string listOf(const std::vector<std::string>& names) {
    std::string text;
    for (size_t i = 0; i < names.size() && i < 20; ++i) text += (i ? ", " : "") + names[i];
    if (names.size() > 20) text += ", ...";
    return text;
}

// Sizes the chunk cache to one layer of chunks across the slice, so reading slices one slab at
// a time decodes each chunk once (the default cache is 1 MiB, less than most layers).
void sizeChunkCache(hid_t dcpl, hid_t dapl, const DatasetShape& s) {
    if (H5Pget_layout(dcpl) != H5D_CHUNKED) return;
    hsize_t chunk[3] = {0, 0, 0};
    if (H5Pget_chunk(dcpl, 3, chunk) != 3 || chunk[0] == 0 || chunk[1] == 0 || chunk[2] == 0) return;
    const double across = std::ceil(double(s.dims[1]) / double(chunk[1])) *
                          std::ceil(double(s.dims[2]) / double(chunk[2]));
    const double bytes = across * double(chunk[0] * chunk[1]) * double(chunk[2]) *
                         double(fileScalarSize(*s.type));
    // A layer beyond 4 GiB is left to HDF5's own cache rather than reserved.
    if (!(bytes > double(1 << 20) && bytes < 0x1p32)) return;
    const size_t slots = size_t(std::min(across * 16.0 + 1.0, 1e7));  // a prime is better; plenty is enough
    H5Pset_chunk_cache(dapl, slots, size_t(bytes), 1.0);
}

// Refuses a filter this HDF5 cannot decode at open, rather than at the first chunk.
void requireFilters(const std::string& where, hid_t dcpl) {
    const int n = H5Pget_nfilters(dcpl);
    for (int i = 0; i < n; ++i) {
        unsigned flags = 0, config = 0;
        size_t nValues = 0;
        char name[128] = {};
        const H5Z_filter_t id =
            H5Pget_filter2(dcpl, unsigned(i), &flags, &nValues, nullptr, sizeof(name), name, &config);
        if (id < 0) continue;
        if (H5Zfilter_avail(id) <= 0) {
            H5Eclear2(H5E_DEFAULT);
            fail(where, "is compressed with HDF5 filter " + std::to_string(id) +
                            (name[0] ? std::string(" (") + name + ")" : "") +
                            ", which this HDF5 cannot decode (is its plugin on "
                            "HDF5_PLUGIN_PATH?)");
        }
    }
}

// element_size_um = (z, y, x), as Fiji and ilastik write it; returned as x, y, z.
std::optional<std::array<double, 3>> elementSize(hid_t dataset) {
    if (H5Aexists(dataset, "element_size_um") <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return std::nullopt;
    }
    Handle attribute(H5Aopen(dataset, "element_size_um", H5P_DEFAULT), H5Aclose);
    if (!attribute.valid()) return std::nullopt;
    Handle space(H5Aget_space(attribute.get()), H5Sclose);
    if (H5Sget_simple_extent_npoints(space.get()) != 3) return std::nullopt;
    double v[3] = {0, 0, 0};
    if (H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, v) < 0) {
        H5Eclear2(H5E_DEFAULT);
        return std::nullopt;
    }
    for (double x : v)
        if (!(std::isfinite(x) && x > 0.0)) return std::nullopt;
    return std::array<double, 3>{v[2], v[1], v[0]};
}

// An open dataset: what vdiso_hdf5_open's handle points to.
struct Dataset {
    std::string where;  // FILE:/dataset
    Handle file, dataset, space;
    Dims3 dims;  // x, y, z
    FileScalar type;
    std::optional<std::array<double, 3>> spacing;
};

// Opens the dataset; throws Failure.
std::unique_ptr<Dataset> openDataset(const std::string& file, const std::string& dataset) {
    silenceHdf5();
    if (H5Fis_hdf5(file.c_str()) <= 0) {
        const std::string why = hdf5Message();
        fail(file, "is not an HDF5 file" + (why.empty() ? std::string() : " (" + why + ")"));
    }
    Handle f(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    if (!f.valid()) fail(file, "cannot be opened as HDF5: " + hdf5Message());
    std::string name = dataset;
    if (name.empty()) {
        DatasetSearch search{f.get(), {}, {}};
        if (H5Lvisit(f.get(), H5_INDEX_NAME, H5_ITER_NATIVE, visitLink, &search) < 0)
            fail(file, "its groups cannot be listed: " + hdf5Message());
        if (search.volumes.size() != 1)
            fail(file, search.volumes.empty()
                           ? "holds no 3-D numeric dataset" +
                                 (search.others.empty() ? std::string()
                                                        : " (it holds " + listOf(search.others) + ")")
                           : "holds several 3-D datasets (" + listOf(search.volumes) +
                                 "): name one as " + file + ":/path");
        name = search.volumes.front();
    }
    const std::string where = file + ":" + name;
    Handle d(H5Dopen2(f.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
    if (!d.valid()) {
        H5Eclear2(H5E_DEFAULT);
        const htri_t exists = H5Lexists(f.get(), name.c_str(), H5P_DEFAULT);
        H5Eclear2(H5E_DEFAULT);
        fail(where, exists > 0 ? "is not a dataset (a group?)" : "no such dataset in the file");
    }
    const DatasetShape shape = shapeOf(d.get());
    if (!shape.problem.empty()) fail(where, shape.problem);
    Handle dcpl(H5Dget_create_plist(d.get()), H5Pclose);
    if (!dcpl.valid()) fail(where, "cannot be read: " + hdf5Message());
    requireFilters(where, dcpl.get());
    const Dims3 dims = {int64_t(shape.dims[2]), int64_t(shape.dims[1]), int64_t(shape.dims[0])};
    // Checked before anything is sized from them (the chunk cache below).
    if (const std::string problem = volumeDimsProblem(dims); !problem.empty()) fail(where, problem);
    const std::optional<std::array<double, 3>> spacing = elementSize(d.get());
    // Reopened with a chunk cache that holds a layer of chunks. Closed first: a dataset opened
    // twice shares one object, whose cache is the one its first opening made (1 MiB), and
    // reading 64^3 chunks slice by slice through that ran at 5 MB/s.
    Handle dapl(H5Pcreate(H5P_DATASET_ACCESS), H5Pclose);
    if (dapl.valid()) {
        sizeChunkCache(dcpl.get(), dapl.get(), shape);
        d = Handle(-1, H5Dclose);
        d = Handle(H5Dopen2(f.get(), name.c_str(), dapl.get()), H5Dclose);
        if (!d.valid()) fail(where, "cannot be reopened: " + hdf5Message());
    }
    Handle space(H5Dget_space(d.get()), H5Sclose);
    if (!space.valid()) fail(where, "cannot be read: " + hdf5Message());
    return std::make_unique<Dataset>(
        Dataset{where, std::move(f), std::move(d), std::move(space), dims, *shape.type, spacing});
}

void readSlab(Dataset& d, int64_t z, int64_t n, void* target) {
    if (z < 0 || n < 0 || z + n > d.dims[2]) fail(d.where, "has fewer slices than asked for");
    if (n == 0) return;
    const hsize_t start[3] = {hsize_t(z), 0, 0};
    const hsize_t size[3] = {hsize_t(n), hsize_t(d.dims[1]), hsize_t(d.dims[0])};
    Handle memory(H5Screate_simple(3, size, nullptr), H5Sclose);
    if (!memory.valid() ||
        H5Sselect_hyperslab(d.space.get(), H5S_SELECT_SET, start, nullptr, size, nullptr) < 0 ||
        H5Dread(d.dataset.get(), nativeType(d.type), memory.get(), d.space.get(), H5P_DEFAULT,
                target) < 0)
        fail(d.where, "slices " + std::to_string(z) + " to " + std::to_string(z + n - 1) +
                          " cannot be read: " + hdf5Message());
}

void copyMessage(const char* message, char* err, size_t errBytes) {
    if (err && errBytes > 0) std::snprintf(err, errBytes, "%s", message);
}

}  // namespace
}  // namespace vdiso

static_assert(int(vdiso::FileScalar::I8) == VDISO_HDF5_I8 && int(vdiso::FileScalar::F64) == VDISO_HDF5_F64);

extern "C" void* vdiso_hdf5_open(const char* file, const char* dataset, VdisoHdf5Dataset* out,
                                 char* err, size_t errBytes) {
    try {
        std::unique_ptr<vdiso::Dataset> d = vdiso::openDataset(file, dataset);
        const std::string name = d->where.substr(std::string(file).size() + 1);
        if (name.size() >= sizeof(out->name))
            vdiso::fail(d->where, "the dataset's path is longer than vdiso takes");
        *out = VdisoHdf5Dataset{};
        for (int a = 0; a < 3; ++a) out->dims[a] = d->dims[size_t(a)];
        out->sampleType = int(d->type);
        out->hasSpacing = d->spacing.has_value();
        if (d->spacing)
            for (int a = 0; a < 3; ++a) out->spacing[a] = (*d->spacing)[size_t(a)];
        std::copy(name.begin(), name.end(), out->name);
        return d.release();
    } catch (const std::exception& e) {
        vdiso::copyMessage(e.what(), err, errBytes);
    } catch (...) {
        vdiso::copyMessage((std::string(file) + ": libhdf5 failed on it").c_str(), err, errBytes);
    }
    return nullptr;
}

extern "C" int vdiso_hdf5_read(void* handle, int64_t firstSlice, int64_t count, void* dst,
                               char* err, size_t errBytes) {
    auto& d = *static_cast<vdiso::Dataset*>(handle);
    try {
        vdiso::readSlab(d, firstSlice, count, dst);
        return 0;
    } catch (const std::exception& e) {
        vdiso::copyMessage(e.what(), err, errBytes);
    } catch (...) {
        vdiso::copyMessage((d.where + ": libhdf5 failed reading it").c_str(), err, errBytes);
    }
    return -1;
}

extern "C" void vdiso_hdf5_close(void* handle) {
    delete static_cast<vdiso::Dataset*>(handle);
}
