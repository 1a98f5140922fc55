#include "cli/convert_args.h"

#include <algorithm>
#include <cstdio>
#include <optional>
#include <utility>

#include "core/orientation.h"

namespace vdiso::cli {

namespace {

std::optional<FileScalar> parseFileScalar(const std::string& name) {
    static const std::pair<const char*, FileScalar> kNames[] = {
        {"u8", FileScalar::U8},   {"i8", FileScalar::I8},   {"i16", FileScalar::I16},
        {"u16", FileScalar::U16}, {"i32", FileScalar::I32}, {"u32", FileScalar::U32},
        {"f32", FileScalar::F32}, {"f64", FileScalar::F64}};
    for (const auto& [n, t] : kNames)
        if (name == n) return t;
    return std::nullopt;
}

}  // namespace

const char* const kConvertInputHelp =
    "input formats (by name): .nrrd .nhdr (NRRD), .nii .nii.gz .hdr (NIfTI-1), .mha .mhd\n"
    "(MetaImage), .h5 .hdf5 (HDF5: FILE.h5:/path/to/dataset, or the file if it holds one 3-D\n"
    "dataset), .vdb (OpenVDB), a Zarr array or OME-Zarr image folder (v2 or v3, sharded too), or\n"
    "one at a URL (https://HOST/PATH.zarr, http://..., s3://BUCKET/PATH.zarr: chunks fetched many\n"
    "at once), .tif .tiff (a multi-page TIFF or BigTIFF); a folder of .tif slices, or a quoted\n"
    "glob such as 'scan/slice_*.tif' (slices in natural order: slice_2 before slice_10); DICOM: a folder\n"
    "(with its subfolders), a DICOMDIR, one .dcm file (its series) or a list of files; anything\n"
    "else is raw and needs --dims and --type.\n"
    "\n"
    "any input:\n"
    "  --spacing S | X,Y,Z     sample spacing, replacing the file's (TIFF has none: default 1)\n"
    "raw input:\n"
    "  --dims X,Y,Z            samples per axis (x fastest in the file)\n"
    "  --type T                u8, i16, u16, f32 (also i8, i32, u32, f64: stored as i16/f32)\n"
    "  --endian little|big     byte order (default little)\n"
    "  --header-bytes N        bytes to skip before the samples (default 0)\n"
    "DICOM input:\n"
    "  --series UID            the series to convert, when the input holds several (the error\n"
    "                          lists them)\n"
    "OME-Zarr input:\n"
    "  --scale-level N         the multiscales level to read (default 0, the finest); named\n"
    "                          so because --level is the store's zstd level\n"
    "OpenVDB input:\n"
    "  --grid NAME             the float grid to convert (default: the first)\n";

bool ConvertArgParser::take(const std::string& a, Args& args) {
    if (a == "--dims") {
        mRaw.dims = parseDims(a, args.value(a));
        mDimsGiven = true;
    } else if (a == "--type") {
        const std::string t = args.value(a);
        const auto type = parseFileScalar(t);
        if (!type)
            throw UsageError("unknown type '" + t + "' (expected u8, i16, u16, f32, i8, i32, u32 or f64)");
        mRaw.type = *type;
        mTypeGiven = true;
    } else if (a == "--spacing") {
        mRaw.spacing = parseSpacing(a, args.value(a));
        mArgs.input.spacing = mRaw.spacing;
    } else if (a == "--endian") {
        const std::string e = args.value(a);
        if (e != "little" && e != "big") throw UsageError("--endian expects little or big");
        mRaw.bigEndian = e == "big";
        mRawOnlyGiven = true;
    } else if (a == "--header-bytes") {
        mRaw.headerBytes = uint64_t(parseInt(a, args.value(a), 0, int64_t(1) << 50));
        mRawOnlyGiven = true;
    } else if (a == "--series") {
        mArgs.input.series = args.value(a);
    } else if (a == "--scale-level") {
        mArgs.input.scaleLevel = int(parseInt(a, args.value(a), 0, 64));
    } else if (a == "--grid") {
        mArgs.input.grid = args.value(a);
    } else if (takeRemoteOption(a, args, mArgs.input.remote)) {
    } else if (takeStoreWriteOption(a, args, mArgs.store)) {
    } else if (a == "--quiet") {
        mArgs.quiet = true;
    } else if (!a.empty() && a[0] == '-' && a != "-") {
        return false;
    } else {
        mPositional.push_back(a);
    }
    return true;
}

ConvertArgs ConvertArgParser::finish() {
    if (mPositional.size() < 2) throw UsageError("expects INPUT and OUTPUT");
    if (mDimsGiven != mTypeGiven) throw UsageError("raw input needs both --dims and --type");
    if (mRawOnlyGiven && !mDimsGiven)
        throw UsageError("--endian and --header-bytes apply to raw input, which needs --dims "
                         "and --type");
    if (mDimsGiven) mArgs.input.raw = mRaw;
    mArgs.output = mPositional.back();
    mPositional.pop_back();
    for (const std::string& inPath : mPositional)
        if (inPath == mArgs.output) throw UsageError("INPUT and OUTPUT are the same file");
    if (mPositional.size() > 1 && mDimsGiven)
        throw UsageError("raw input is one file: expects INPUT and OUTPUT");
    mArgs.inputs = mPositional;
    return mArgs;
}

void printConvertSummary(const std::string& output, const std::string& where, const VolumeInfo& info,
                         const StoreWriteSummary& s, int brickSize, const std::string& sourceName) {
    std::printf("wrote %s%s: %lldx%lldx%lld %s, %lld bricks of %d^3 cells in %d level%s (coarse "
                "levels +%.1f%%), %.1f MB in, %.1f MB stored (ratio %.2f), %.2f s, %.0f MB/s\n",
                output.c_str(), where.c_str(), (long long)info.dims[0], (long long)info.dims[1],
                (long long)info.dims[2], scalarTypeName(info.type), (long long)s.bricks, brickSize, s.levels,
                s.levels == 1 ? "" : "s", 100.0 * double(s.coarseBytes) / double(std::max<uint64_t>(s.level0Bytes, 1)),
                s.inputBytes / 1e6, s.fileBytes / 1e6, double(s.inputBytes) / double(s.fileBytes), s.seconds,
                s.inputBytes / 1e6 / s.seconds);
    // Whether meshes will land in patient space: worth a line, as a file may lack it silently.
    std::printf(info.hasOrientation ? "  orientation: axes i, j, k toward %s (meshes are written in LPS)\n"
                                    : "  orientation: none in %s (meshes are written in volume space)\n",
                info.hasOrientation ? axisSidesCode(info.direction).c_str() : sourceName.c_str());
}

}  // namespace vdiso::cli
