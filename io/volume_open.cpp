#include "io/volume_open.h"

#include <stdexcept>

#include "io/error.h"
#include "io/file_names.h"
#include "io/nifti_reader.h"
#include "io/nrrd_reader.h"
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

}  // namespace

InputFormat detectInputFormat(const std::string& path, const InputOptions& options) {
    if (options.raw) return InputFormat::Raw;
    if (endsWithIgnoreCase(path, ".nrrd") || endsWithIgnoreCase(path, ".nhdr"))
        return InputFormat::Nrrd;
    for (const char* suffix : {".nii", ".nii.gz", ".hdr", ".hdr.gz", ".img", ".img.gz"})
        if (endsWithIgnoreCase(path, suffix)) return InputFormat::Nifti;
    if (endsWithIgnoreCase(path, ".vdb")) return InputFormat::Vdb;
    throwIoError(path, "unknown input format (expected .nrrd, .nhdr, .nii, .nii.gz, .hdr/.img "
                       "or .vdb; for a raw file give --dims and --type)");
}

std::unique_ptr<SliceReader> openVolume(const std::string& path, const InputOptions& options) {
    switch (detectInputFormat(path, options)) {
        case InputFormat::Raw: return openRawVolume(path, *options.raw);
        case InputFormat::Nrrd: return openNrrdVolume(path);
        case InputFormat::Nifti: return openNiftiVolume(path);
        case InputFormat::Vdb: break;
    }
    return openVdbVolume(path, options.grid);
}

std::unique_ptr<SliceReader> openSynthVolume(const SynthParams& params) {
    for (int a = 0; a < 3; ++a)
        if (params.dims[a] < 2)
            throw std::invalid_argument("synthetic volumes need at least 2 samples per axis");
    return std::make_unique<SynthSliceReader>(params);
}

}  // namespace vdiso
