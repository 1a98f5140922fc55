#include "io/vdb_reader.h"

#include <dlfcn.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "io/error.h"
#include "io/vdb_module/vdb_module.h"

namespace vdiso {
namespace {

constexpr const char* kModuleName = "libvdiso_vdb.so";

struct VdbModule {
    decltype(&vdiso_vdb_open) open = nullptr;
    decltype(&vdiso_vdb_read) read = nullptr;
    decltype(&vdiso_vdb_close) close = nullptr;
};

// Where the module is: in VDISO_MODULE_DIR when that is set; otherwise beside the running
// executable (where the build puts it, next to vdiso), else in the build tree's directory for it.
std::vector<std::string> moduleCandidates() {
    std::vector<std::string> dirs;
    if (const char* dir = std::getenv("VDISO_MODULE_DIR"))
        return {std::string(dir) + "/" + kModuleName};
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) dirs.push_back(exe.parent_path().string());
#ifdef VDISO_BUILD_MODULE_DIR
    dirs.emplace_back(VDISO_BUILD_MODULE_DIR);
#endif
    std::vector<std::string> paths;
    for (const std::string& d : dirs) paths.push_back(d + "/" + kModuleName);
    return paths;
}

// Loaded on first use; throws IoError naming `path` (the file being read) when it cannot be.
const VdbModule& vdbModule(const std::string& path) {
    static const VdbModule* loaded = [] () -> const VdbModule* {
        void* library = nullptr;
        for (const std::string& candidate : moduleCandidates()) {
            if (::access(candidate.c_str(), R_OK) != 0) continue;
            library = ::dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
            if (library) break;
        }
        if (!library) return nullptr;
        static VdbModule m;
        m.open = reinterpret_cast<decltype(m.open)>(::dlsym(library, "vdiso_vdb_open"));
        m.read = reinterpret_cast<decltype(m.read)>(::dlsym(library, "vdiso_vdb_read"));
        m.close = reinterpret_cast<decltype(m.close)>(::dlsym(library, "vdiso_vdb_close"));
        return m.open && m.read && m.close ? &m : nullptr;
    }();
    if (!loaded)
        throwIoError(path, std::string("reading OpenVDB files needs the module ") + kModuleName +
                               ", which was not found or did not load (the build puts it beside "
                               "vdiso; VDISO_MODULE_DIR says where else to look)");
    return *loaded;
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

    std::string name() const override { return mPath; }

private:
    static const std::string& requireReadable(const std::string& path) {
        std::FILE* f = std::fopen(path.c_str(), "rb");
        if (!f) throwSystemError(path, "cannot open", errno);
        std::fclose(f);
        return path;
    }

    std::string mPath;
    const VdbModule& mModule;
    void* mHandle = nullptr;
    VolumeInfo mInfo;
    int64_t mNextZ = 0;
};

}  // namespace

std::unique_ptr<SliceReader> openVdbVolume(const std::string& path, const std::string& gridName) {
    return std::make_unique<VdbSliceReader>(path, gridName);
}

}  // namespace vdiso
