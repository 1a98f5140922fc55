#include "io/volume_open.h"

#include <filesystem>
#include <stdexcept>
#include <utility>

#include "io/error.h"
#include "io/file_list.h"
#include "io/file_names.h"
#include "io/nifti_reader.h"
#include "io/nrrd_reader.h"
#include "io/tiff_reader.h"
#include "io/vdb_reader.h"

namespace vdiso {

namespace {

class SynthSliceReader final : public SliceReader {
public:
    explicit SynthSliceReader(const SynthParams& p) : mParams(p) {
        mInfo.dims = p.dims;
        mInfo.type = p.type;
    }
    const VolumeInfo& info() const override { return mInfo; }
    void read(void* dst, int64_t count) override {
        synthesizeSlices(mParams, mNextZ, count, dst);
        mNextZ += count;
    }
    std::string name() const override {
        return mParams.kind == SynthKind::Head ? "synth:head" : "synth:turbulence";
    }

private:
    SynthParams mParams;
    VolumeInfo mInfo;
    int64_t mNextZ = 0;
};

// A reader whose spacing is the user's (--spacing), not the file's.
class SpacingOverride final : public SliceReader {
public:
    SpacingOverride(std::unique_ptr<SliceReader> inner, const glm::dvec3& spacing)
        : mInner(std::move(inner)), mInfo(mInner->info()) {
        mInfo.spacing = spacing;
    }
    const VolumeInfo& info() const override { return mInfo; }
    void read(void* dst, int64_t count) override { mInner->read(dst, count); }
    void finish() override { mInner->finish(); }
    std::string name() const override { return mInner->name(); }
    std::vector<std::string> files() const override { return mInner->files(); }

private:
    std::unique_ptr<SliceReader> mInner;
    VolumeInfo mInfo;
};

const char* const kKnownInputs =
    "expected .nrrd, .nhdr, .nii, .nii.gz, .hdr/.img, .vdb, .tif/.tiff, or a folder of TIFF "
    "slices; for a raw file give --dims and --type";

InputFormat detectFolderFormat(const std::string& path) {
    if (!listFolder(path, {".tif", ".tiff"}).empty()) return InputFormat::Tiff;
    throwIoError(path, std::string("is a folder holding no volume vdiso reads (") + kKnownInputs +
                           ")");
}

}  // namespace

InputFormat detectInputFormat(const std::string& path, const InputOptions& options) {
    if (options.raw) return InputFormat::Raw;
    if (endsWithIgnoreCase(path, ".nrrd") || endsWithIgnoreCase(path, ".nhdr"))
        return InputFormat::Nrrd;
    for (const char* suffix : {".nii", ".nii.gz", ".hdr", ".hdr.gz", ".img", ".img.gz"})
        if (endsWithIgnoreCase(path, suffix)) return InputFormat::Nifti;
    if (endsWithIgnoreCase(path, ".vdb")) return InputFormat::Vdb;
    for (const char* suffix : {".tif", ".tiff", ".btf", ".tf8"})
        if (endsWithIgnoreCase(path, suffix)) return InputFormat::Tiff;
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) return detectFolderFormat(path);
    const bool exists = std::filesystem::exists(path, ec);
    if (!exists && isGlobPattern(path)) return InputFormat::Tiff;
    if (exists && hasTiffMagic(path)) return InputFormat::Tiff;
    throwIoError(path, std::string("unknown input format (") + kKnownInputs + ")");
}

namespace {

std::unique_ptr<SliceReader> openInFormat(const std::string& path, const InputOptions& options) {
    switch (detectInputFormat(path, options)) {
        case InputFormat::Raw: return openRawVolume(path, *options.raw);
        case InputFormat::Nrrd: return openNrrdVolume(path);
        case InputFormat::Nifti: return openNiftiVolume(path);
        case InputFormat::Tiff: return openTiffVolume(path);
        case InputFormat::Vdb: break;
    }
    return openVdbVolume(path, options.grid);
}

}  // namespace

std::unique_ptr<SliceReader> openVolume(const std::string& path, const InputOptions& options) {
    auto reader = openInFormat(path, options);
    if (!options.spacing || options.raw) return reader;
    return std::make_unique<SpacingOverride>(std::move(reader), *options.spacing);
}

std::unique_ptr<SliceReader> openSynthVolume(const SynthParams& params) {
    for (int a = 0; a < 3; ++a)
        if (params.dims[a] < 2)
            throw std::invalid_argument("synthetic volumes need at least 2 samples per axis");
    return std::make_unique<SynthSliceReader>(params);
}

}  // namespace vdiso
