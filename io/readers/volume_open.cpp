#include "io/readers/volume_open.h"

#include <filesystem>
#include <stdexcept>
#include <utility>

#include "io/readers/dicom_reader.h"
#include "io/error.h"
#include "io/readers/file_list.h"
#include "io/readers/file_names.h"
#include "io/readers/hdf5_reader.h"
#include "io/readers/metaimage_reader.h"
#include "io/readers/nifti_reader.h"
#include "io/readers/nrrd_reader.h"
#include "io/readers/tiff_reader.h"
#include "io/remote/remote_file.h"
#include "io/readers/zarr_reader.h"
#include "io/readers/vdb_reader.h"

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
    // Each slice is a function of its z: passing over slices generates none.
    void skip(int64_t count) override {
        if (count < 0 || count > mInfo.dims[2] - mNextZ)
            throwIoError(name(), "has fewer slices than asked for");
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
    void skip(int64_t count) override { mInner->skip(count); }
    void finish() override { mInner->finish(); }
    std::string name() const override { return mInner->name(); }
    std::vector<std::string> files() const override { return mInner->files(); }

private:
    std::unique_ptr<SliceReader> mInner;
    VolumeInfo mInfo;
};

const char* const kKnownInputs =
    "expected .nrrd, .nhdr, .nii, .nii.gz, .hdr/.img, .mha/.mhd, .h5[:/dataset], .vdb, "
    ".tif/.tiff, .dcm, a DICOMDIR, a Zarr or OME-Zarr folder, or a folder of TIFF slices or "
    "DICOM files; for a raw file give --dims and --type";

// A name that says a format vdiso reads from local files only.
bool looksLikeLocalOnlyFormat(const std::string& path) {
    const std::string name = path.substr(0, path.find_first_of("?#"));
    for (const char* suffix : {".nrrd", ".nhdr", ".nii", ".nii.gz", ".hdr", ".img", ".vdb", ".mha",
                               ".mhd", ".h5", ".hdf5", ".tif", ".tiff", ".dcm", ".raw", ".vdiso"})
        if (endsWithIgnoreCase(name, suffix)) return true;
    return false;
}

InputFormat detectFolderFormat(const std::string& path) {
    if (looksLikeZarr(path)) return InputFormat::Zarr;
    if (!listFolder(path, {".tif", ".tiff"}).empty()) return InputFormat::Tiff;
    if (looksLikeDicomFolder(path)) return InputFormat::Dicom;
    throwIoError(path, std::string("is a folder holding no volume vdiso reads (") + kKnownInputs +
                           ")");
}

}  // namespace

InputFormat detectInputFormat(const std::string& path, const InputOptions& options) {
    // Over the network, chunked formats only: each chunk is fetched when its layer is read.
    if (isRemoteLocation(path)) {
        if (options.raw || looksLikeLocalOnlyFormat(path))
            throwIoError(displayLocation(path), "is read from a URL only as Zarr or OME-Zarr (a "
                                                "prefix holding .zarray, .zattrs or zarr.json): "
                                                "download other formats first");
        return InputFormat::Zarr;
    }
    if (options.raw) return InputFormat::Raw;
    if (endsWithIgnoreCase(path, ".nrrd") || endsWithIgnoreCase(path, ".nhdr"))
        return InputFormat::Nrrd;
    for (const char* suffix : {".nii", ".nii.gz", ".hdr", ".hdr.gz", ".img", ".img.gz"})
        if (endsWithIgnoreCase(path, suffix)) return InputFormat::Nifti;
    if (endsWithIgnoreCase(path, ".vdb")) return InputFormat::Vdb;
    if (endsWithIgnoreCase(path, ".mha") || endsWithIgnoreCase(path, ".mhd"))
        return InputFormat::MetaImage;
    if (splitHdf5Path(path)) return InputFormat::Hdf5;
    for (const char* suffix : {".tif", ".tiff", ".btf", ".tf8"})
        if (endsWithIgnoreCase(path, suffix)) return InputFormat::Tiff;
    for (const char* suffix : {".dcm", ".dicom", ".ima", "/DICOMDIR"})
        if (endsWithIgnoreCase(path, suffix) || path == "DICOMDIR") return InputFormat::Dicom;
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) return detectFolderFormat(path);
    const bool exists = std::filesystem::exists(path, ec);
    if (!exists && isGlobPattern(path)) return InputFormat::Tiff;
    if (exists && hasTiffMagic(path)) return InputFormat::Tiff;
    if (exists && hasDicomMagic(path)) return InputFormat::Dicom;
    throwIoError(path, std::string("unknown input format (") + kKnownInputs + ")");
}

namespace {

std::unique_ptr<SliceReader> openInFormat(const std::string& path, const InputOptions& options) {
    switch (detectInputFormat(path, options)) {
        case InputFormat::Raw: return openRawVolume(path, *options.raw);
        case InputFormat::Nrrd: return openNrrdVolume(path);
        case InputFormat::Nifti: return openNiftiVolume(path);
        case InputFormat::Tiff: return openTiffVolume(path);
        case InputFormat::Dicom: return openDicomVolume(path, options.series);
        case InputFormat::MetaImage: return openMetaImageVolume(path);
        case InputFormat::Hdf5: return openHdf5Volume(path);
        case InputFormat::Zarr: return openZarrVolume(path, options.scaleLevel, options.remote);
        case InputFormat::Vdb: break;
    }
    return openVdbVolume(path, options.grid);
}

std::unique_ptr<SliceReader> withOptions(std::unique_ptr<SliceReader> reader,
                                         const InputOptions& options) {
    if (!options.spacing || options.raw) return reader;
    return std::make_unique<SpacingOverride>(std::move(reader), *options.spacing);
}

void requireFormatOptions(const std::string& path, InputFormat format,
                               const InputOptions& options) {
    if (!options.series.empty() && format != InputFormat::Dicom)
        throwIoError(path, "is not DICOM: a series can be chosen in DICOM input only");
    if (options.scaleLevel != 0 && format != InputFormat::Zarr)
        throwIoError(path, "is not Zarr: a scale level can be chosen in OME-Zarr input only");
}

}  // namespace

std::unique_ptr<SliceReader> openVolume(const std::string& path, const InputOptions& options) {
    requireFormatOptions(path, detectInputFormat(path, options), options);
    return withOptions(openInFormat(path, options), options);
}

std::unique_ptr<SliceReader> openVolume(const std::vector<std::string>& paths,
                                        const InputOptions& options) {
    if (paths.size() == 1) return openVolume(paths.front(), options);
    if (paths.empty()) throw IoError("no input given");
    if (options.raw) throwIoError(paths.front(), "raw input is one file, not a list");
    const InputFormat format = detectInputFormat(paths.front(), options);
    for (const std::string& p : paths)
        if (detectInputFormat(p, options) != format)
            throwIoError(p, "is in another format than " + paths.front() +
                                ": a list of inputs must be slices of one volume");
    requireFormatOptions(paths.front(), format, options);
    if (format == InputFormat::Dicom)
        return withOptions(openDicomFiles(paths, options.series), options);
    if (format == InputFormat::Tiff) return withOptions(openTiffSlices(paths), options);
    throwIoError(paths.front(), "is one volume: only DICOM files and TIFF slices may be given as a "
                                "list");
}

std::unique_ptr<SliceReader> openSynthVolume(const SynthParams& params) {
    for (int a = 0; a < 3; ++a)
        if (params.dims[a] < 2)
            throw std::invalid_argument("synthetic volumes need at least 2 samples per axis");
    return std::make_unique<SynthSliceReader>(params);
}

}  // namespace vdiso
