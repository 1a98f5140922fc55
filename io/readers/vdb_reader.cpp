#include "io/readers/vdb_reader.h"

#include <array>
#include <cerrno>
#include <cstdio>
#include <string>

#include "io/error.h"
#include "io/readers/run_time_module.h"
#include "io/readers/vdb_module/vdb_module.h"

namespace vdiso {
namespace {

constexpr const char* kModuleName = "libvdiso_vdb.so";

struct VdbModule {
    decltype(&vdiso_vdb_open) open = nullptr;
    decltype(&vdiso_vdb_read) read = nullptr;
    decltype(&vdiso_vdb_close) close = nullptr;
};

// Loaded on first use (io/readers/run_time_module.h); throws IoError naming `path` (the file being
// read) when it cannot be.
VdbModule vdbModule(const std::string& path) {
    auto symbol = [&](const char* name) {
        return runTimeModuleSymbol(kModuleName, name, path, "reading OpenVDB files");
    };
    VdbModule m;
    m.open = reinterpret_cast<decltype(m.open)>(symbol("vdiso_vdb_open"));
    m.read = reinterpret_cast<decltype(m.read)>(symbol("vdiso_vdb_read"));
    m.close = reinterpret_cast<decltype(m.close)>(symbol("vdiso_vdb_close"));
    return m;
}

class VdbSliceReader final : public SliceReader {
public:
    VdbSliceReader(const std::string& path, const std::string& gridName)
        : mPath(path), mModule(vdbModule(requireReadable(path))) {
        VdisoVdbVolume volume{};
        std::array<char, 1024> err{};
        mHandle = mModule.open(path.c_str(), gridName.c_str(), &volume, err.data(), err.size());
        if (!mHandle) throwIoError(path, err.data());
        mInfo.dims = {volume.dims[0], volume.dims[1], volume.dims[2]};
        mInfo.type = ScalarType::F32;
        mInfo.spacing = {volume.spacing[0], volume.spacing[1], volume.spacing[2]};
        mInfo.origin = {volume.origin[0], volume.origin[1], volume.origin[2]};
        const std::string problem = volumeDimsProblem(mInfo.dims);
        if (!problem.empty()) {
            mModule.close(mHandle);
            throwIoError(path, "active voxels' bounding box of " + problem);
        }
    }
    ~VdbSliceReader() override { mModule.close(mHandle); }
    VdbSliceReader(const VdbSliceReader&) = delete;
    VdbSliceReader& operator=(const VdbSliceReader&) = delete;

    const VolumeInfo& info() const override { return mInfo; }
    std::vector<std::string> files() const override { return {mPath}; }

    void read(void* dst, int64_t count) override {
        if (count < 0 || mNextZ + count > mInfo.dims[2])
            throwIoError(mPath, "read of " + std::to_string(count) + " slices from slice " +
                                    std::to_string(mNextZ) + " runs past the grid's " +
                                    std::to_string(mInfo.dims[2]));
        if (count == 0) return;
        std::array<char, 1024> err{};
        if (mModule.read(mHandle, mNextZ, count, static_cast<float*>(dst), err.data(), err.size()) != 0)
            throwIoError(mPath, err.data());
        mNextZ += count;
    }

    // Each read samples the grid from slice mNextZ: passing over slices samples none.
    void skip(int64_t count) override {
        if (count < 0 || mNextZ + count > mInfo.dims[2])
            throwIoError(mPath, "skip of " + std::to_string(count) + " slices from slice " +
                                    std::to_string(mNextZ) + " runs past the grid's " +
                                    std::to_string(mInfo.dims[2]));
        mNextZ += count;
    }

    std::string name() const override { return mPath; }

private:
    static const std::string& requireReadable(const std::string& path) {
        std::FILE* f = std::fopen(path.c_str(), "rb");
        if (!f) throwSystemError(path, "cannot open", errno);
        std::fclose(f);
        return path;
    }

    std::string mPath;
    VdbModule mModule;
    void* mHandle = nullptr;
    VolumeInfo mInfo;
    int64_t mNextZ = 0;
};

}  // namespace

std::unique_ptr<SliceReader> openVdbVolume(const std::string& path, const std::string& gridName) {
    return std::make_unique<VdbSliceReader>(path, gridName);
}

}  // namespace vdiso
