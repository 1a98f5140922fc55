#include "io/readers/hdf5_reader.h"

#include <algorithm>
#include <array>
#include <vector>

#include "core/interrupt.h"
#include "io/error.h"
#include "io/readers/file_names.h"
#include "io/readers/hdf5_module/hdf5_module.h"
#include "io/readers/isolated_reader.h"
#include "io/readers/run_time_module.h"
#include "io/readers/sample_decode.h"

namespace vdiso {
namespace {

constexpr const char* kSuffixes[] = {".h5", ".hdf5", ".he5", ".hdf"};
constexpr const char* kModuleName = "libvdiso_hdf5_module.so";

struct Hdf5Module {
    decltype(&vdiso_hdf5_open) open = nullptr;
    decltype(&vdiso_hdf5_read) read = nullptr;
    decltype(&vdiso_hdf5_close) close = nullptr;
};

// Loaded on first use (io/readers/run_time_module.h), in vdiso: the helpers forked after inherit it
// rather than each paying libhdf5's loading. Throws IoError naming `file` when it cannot be.
Hdf5Module hdf5Module(const std::string& file) {
    auto symbol = [&](const char* name) {
        return runTimeModuleSymbol(kModuleName, name, file, "reading HDF5 files");
    };
    Hdf5Module m;
    m.open = reinterpret_cast<decltype(m.open)>(symbol("vdiso_hdf5_open"));
    m.read = reinterpret_cast<decltype(m.read)>(symbol("vdiso_hdf5_read"));
    m.close = reinterpret_cast<decltype(m.close)>(symbol("vdiso_hdf5_close"));
    return m;
}

// Runs in the helper process: the module's dataset, converted to its store type.
class Hdf5SliceReader final : public SliceReader {
public:
    Hdf5SliceReader(const Hdf5Module& module, const std::string& file, const std::string& dataset)
        : mModule(module), mFile(file) {
        VdisoHdf5Dataset d{};
        std::array<char, 2048> err{};
        mHandle = mModule.open(file.c_str(), dataset.c_str(), &d, err.data(), err.size());
        if (!mHandle) throw IoError(err.data());
        mName = file + ":" + d.name;
        mType = FileScalar(d.sampleType);
        mInfo.dims = {d.dims[0], d.dims[1], d.dims[2]};
        mInfo.type = storeTypeFor(mType, false);
        if (d.hasSpacing) mInfo.spacing = {d.spacing[0], d.spacing[1], d.spacing[2]};
    }
    ~Hdf5SliceReader() override { mModule.close(mHandle); }
    Hdf5SliceReader(const Hdf5SliceReader&) = delete;
    Hdf5SliceReader& operator=(const Hdf5SliceReader&) = delete;

    const VolumeInfo& info() const override { return mInfo; }

    void read(void* dst, int64_t count) override {
        auto* out = static_cast<unsigned char*>(dst);
        const bool direct = fileScalarOf(mInfo.type) == mType;
        const size_t sliceSamples = size_t(mInfo.sliceSamples());
        const size_t outSlice = sliceSamples * scalarSize(mInfo.type);
        // Direct: the whole slab in one read; converted: a slice at a time through scratch.
        const int64_t step = direct ? count : 1;
        for (int64_t s = 0; s < count; s += step) {
            throwIfInterrupted(mName);
            const int64_t n = std::min(step, count - s);
            if (mNext + n > mInfo.dims[2]) throwIoError(mName, "has fewer slices than asked for");
            if (!direct) mScratch.resize(sliceSamples * fileScalarSize(mType));
            void* target = direct ? static_cast<void*>(out + size_t(s) * outSlice) : mScratch.data();
            std::array<char, 2048> err{};
            if (mModule.read(mHandle, mNext, n, target, err.data(), err.size()) != 0)
                throw IoError(err.data());
            if (!direct)
                decodeSamples(mScratch.data(), mType, false, sliceSamples,
                              out + size_t(s) * outSlice, mInfo.type);
            mNext += n;
        }
    }

    // Each read is a hyperslab from slice mNext: passing over slices reads none.
    void skip(int64_t count) override {
        if (count < 0 || count > mInfo.dims[2] - mNext) throwIoError(mName, "has fewer slices than asked for");
        mNext += count;
    }

    std::string name() const override { return mName; }
    std::vector<std::string> files() const override { return {mFile}; }

private:
    Hdf5Module mModule;
    void* mHandle = nullptr;
    std::string mName, mFile;
    VolumeInfo mInfo;
    FileScalar mType = FileScalar::U8;
    int64_t mNext = 0;
    std::vector<unsigned char> mScratch;
};

}  // namespace

std::optional<std::pair<std::string, std::string>> splitHdf5Path(const std::string& path) {
    for (const char* suffix : kSuffixes) {
        if (endsWithIgnoreCase(path, suffix)) return std::make_pair(path, std::string());
        const std::string withColon = std::string(suffix) + ":";
        for (size_t at = path.find(':'); at != std::string::npos; at = path.find(':', at + 1))
            if (endsWithIgnoreCase(path.substr(0, at + 1), withColon))
                return std::make_pair(path.substr(0, at), path.substr(at + 1));
    }
    return std::nullopt;
}

std::unique_ptr<SliceReader> openHdf5Volume(const std::string& path) {
    const auto parts = splitHdf5Path(path);
    if (!parts) throwIoError(path, "names no HDF5 file (FILE.h5 or FILE.h5:/dataset)");
    return openHdf5Dataset(parts->first, parts->second);
}

std::unique_ptr<SliceReader> openHdf5Dataset(const std::string& file, const std::string& dataset) {
    // libhdf5 1.10 allocates and fills what a damaged file claims (4 GB for a 1 KB superblock,
    // found by fuzz_hdf5): it runs in a helper process, bounded while it opens the file.
    const std::string name = dataset.empty() ? file : file + ":" + dataset;
    const Hdf5Module module = hdf5Module(name);
    return openIsolatedReader(name, "libhdf5", [&] {
        return std::make_unique<Hdf5SliceReader>(module, file, dataset);
    });
}

}  // namespace vdiso
