#include "io/readers/nifti_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>

#include "core/orientation.h"
#include "io/readers/byte_stream.h"
#include "io/error.h"
#include "io/readers/file_names.h"
#include "io/readers/raw_reader.h"
#include "io/readers/sample_decode.h"

namespace vdiso {
namespace {

constexpr size_t kNifti1HeaderSize = 348;
constexpr int32_t kNifti2HeaderSize = 540;

// Byte offsets of the nifti_1_header fields we read.
constexpr size_t kOffDim = 40;  // short[8]
constexpr size_t kOffDatatype = 70;
constexpr size_t kOffPixdim = 76;  // float[8]
constexpr size_t kOffVoxOffset = 108;
constexpr size_t kOffSclSlope = 112;
constexpr size_t kOffSclInter = 116;
constexpr size_t kOffQformCode = 252;
constexpr size_t kOffSformCode = 254;
constexpr size_t kOffQuatern = 256;  // float b, c, d
constexpr size_t kOffQoffset = 268;  // float x, y, z
constexpr size_t kOffSrowX = 280;    // float[4] per row; [3] is the translation
constexpr size_t kSrowStride = 16;
constexpr size_t kOffMagic = 344;

// The 348 header bytes as stored, read in the file's byte order.
class NiftiHeaderBytes {
public:
    unsigned char bytes[kNifti1HeaderSize];
    bool bigEndian = false;

    template <class T>
    T at(size_t offset) const {
        unsigned char b[sizeof(T)];
        if (bigEndian != hostIsBigEndian())
            std::reverse_copy(bytes + offset, bytes + offset + sizeof(T), b);
        else
            std::memcpy(b, bytes + offset, sizeof(T));
        T v;
        std::memcpy(&v, b, sizeof(T));
        return v;
    }
    int16_t i16(size_t offset) const { return at<int16_t>(offset); }
    float f32(size_t offset) const { return at<float>(offset); }
};

struct NiftiHeader {
    Dims3 dims{0, 0, 0};
    FileScalar type = FileScalar::U8;
    bool bigEndian = false;
    bool singleFile = true;  // "n+1"; "ni1" keeps the samples in a separate .img
    uint64_t voxOffset = 0;
    glm::dvec3 spacing{1.0, 1.0, 1.0};
    glm::dvec3 origin{0.0, 0.0, 0.0};
    glm::dmat3 direction{1.0};  // LPS
    bool hasOrientation = false;
    bool scaled = false;
    double slope = 1.0, intercept = 0.0;
};

bool fileExists(const std::string& path) {
    std::error_code ec;
    return std::filesystem::is_regular_file(path, ec);
}

std::string toUpper(std::string s) {
    for (char& c : s) c = char(std::toupper(static_cast<unsigned char>(c)));
    return s;
}

// "x.img" -> "x.hdr": the first of x.hdr, x.hdr.gz, X.HDR, X.HDR.GZ that exists (the spelling
// matching the given name first), else the matching spelling, for the error that follows.
std::string companionFile(const std::string& path, const std::string& fromExt,
                          const std::string& toExt) {
    const bool gz = endsWithIgnoreCase(path, fromExt + ".gz");
    if (!gz && !endsWithIgnoreCase(path, fromExt))
        throwIoError(path, "has magic 'ni1' (samples in a separate " + toExt +
                               " file) but is not named *" + fromExt);
    const size_t extSize = fromExt.size() + (gz ? 3 : 0);
    const std::string stem = path.substr(0, path.size() - extSize);
    const bool upper = std::isupper(static_cast<unsigned char>(path.back()));
    const std::string ext = upper ? toUpper(toExt) : toExt;
    const std::string otherExt = upper ? toExt : toUpper(toExt);
    const std::string gzExt = upper ? ".GZ" : ".gz";
    const std::string candidates[] = {
        stem + ext + (gz ? gzExt : ""),
        stem + ext + (gz ? "" : gzExt),
        stem + otherExt + (gz ? ".gz" : ""),
        stem + otherExt + (gz ? "" : ".gz"),
    };
    for (const std::string& candidate : candidates)
        if (fileExists(candidate)) return candidate;
    return candidates[0];
}

bool isImageFileName(const std::string& path) {
    return endsWithIgnoreCase(path, ".img") || endsWithIgnoreCase(path, ".img.gz");
}

std::unique_ptr<ByteStream> openMaybeGzip(const std::string& path) {
    return hasGzipMagic(path) ? openGzipStream(path) : openFileStream(path);
}

int32_t byteSwapped(int32_t v) {
    uint32_t u;
    std::memcpy(&u, &v, 4);
    u = (u >> 24) | ((u >> 8) & 0xff00u) | ((u << 8) & 0xff0000u) | (u << 24);
    std::memcpy(&v, &u, 4);
    return v;
}

// Like ByteStream::readExact, but a short file is reported against the header it should hold.
size_t readUpTo(ByteStream& in, unsigned char* dst, size_t n) {
    size_t got = 0;
    while (got < n) {
        const size_t r = in.read(dst + got, n - got);
        if (r == 0) break;
        got += r;
    }
    return got;
}

NiftiHeaderBytes readNiftiHeaderBytes(const std::string& path) {
    NiftiHeaderBytes h;
    auto in = openMaybeGzip(path);
    const size_t got = readUpTo(*in, h.bytes, kNifti1HeaderSize);
    if (got < 4)
        throwIoError(
            path, "not a NIfTI-1 file (" + std::to_string(got) + " bytes, too short for a header)");
    int32_t sizeofHdr;
    std::memcpy(&sizeofHdr, h.bytes, 4);
    if (hostIsBigEndian()) sizeofHdr = byteSwapped(sizeofHdr);  // now read as little-endian
    if (sizeofHdr == kNifti2HeaderSize || byteSwapped(sizeofHdr) == kNifti2HeaderSize)
        throwIoError(path, "NIfTI-2 is not supported (sizeof_hdr is 540); save it as NIfTI-1");
    if (sizeofHdr == int32_t(kNifti1HeaderSize))
        h.bigEndian = false;
    else if (byteSwapped(sizeofHdr) == int32_t(kNifti1HeaderSize))
        h.bigEndian = true;
    else
        throwIoError(
            path, "not a NIfTI-1 file (sizeof_hdr is " + std::to_string(sizeofHdr) + ", not 348)");
    if (got < kNifti1HeaderSize)
        throwIoError(path, "ends after " + std::to_string(got) +
                               " bytes, inside its 348-byte NIfTI-1 header");
    return h;
}

const char* niftiDatatypeName(int code) {
    switch (code) {
        case 1:
            return "binary";
        case 32:
            return "complex64";
        case 128:
            return "rgb24";
        case 1024:
            return "int64";
        case 1280:
            return "uint64";
        case 1536:
            return "float128";
        case 1792:
            return "complex128";
        case 2048:
            return "complex256";
        case 2304:
            return "rgba32";
    }
    return "unknown";
}

std::optional<FileScalar> niftiDatatypeToFileScalar(int code) {
    switch (code) {
        case 2:
            return FileScalar::U8;
        case 4:
            return FileScalar::I16;
        case 8:
            return FileScalar::I32;
        case 16:
            return FileScalar::F32;
        case 64:
            return FileScalar::F64;
        case 256:
            return FileScalar::I8;
        case 512:
            return FileScalar::U16;
        case 768:
            return FileScalar::U32;
    }
    return std::nullopt;
}

std::string dimsText(const Dims3& dims) {
    return std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]);
}

Dims3 niftiDims(const std::string& path, const NiftiHeaderBytes& b) {
    const int rank = b.i16(kOffDim);
    if (rank < 1 || rank > 7)
        throwIoError(path, "dim[0] is " + std::to_string(rank) + "; a NIfTI rank is 1 to 7");
    if (rank < 3)
        throwIoError(path, "is " + std::to_string(rank) + "-D (dim[0] = " + std::to_string(rank) +
                               "); only 3-D volumes are supported");
    int64_t frames = 1;
    for (int d = 4; d <= rank; ++d) frames *= std::max<int64_t>(b.i16(kOffDim + 2 * d), 0);
    if (frames != 1)
        throwIoError(path, "has " + std::to_string(frames) +
                               " frames; only single 3-D volumes are supported");
    Dims3 dims;
    for (int a = 0; a < 3; ++a) dims[a] = b.i16(kOffDim + 2 * (a + 1));
    for (int64_t d : dims)
        if (d < 2)
            throwIoError(path, "dims " + dimsText(dims) + ": every axis needs at least 2 samples");
    requireVolumeDims(path, dims);
    return dims;
}

uint64_t niftiVoxOffset(const std::string& path, const NiftiHeaderBytes& b, bool singleFile) {
    const float v = b.f32(kOffVoxOffset);
    if (!std::isfinite(v) || v < 0.0f || v != std::floor(v) || v > 0x1p40f)
        throwIoError(path, "vox_offset " + std::to_string(v) + " is not a valid byte offset");
    if (singleFile && v < float(kNifti1HeaderSize))
        throwIoError(
            path, "vox_offset " + std::to_string(int64_t(v)) + " lies inside the 348-byte header");
    return uint64_t(v);
}

// NIfTI says: no scaling when the slope is 0. A NaN slope means the same: nibabel writes it for
// unscaled images and nifti1_io reads it as 0. Slope 1 with intercept 0 is scaling that changes
// nothing, and skipping it keeps the file's integer type in the store.
void niftiScaling(const std::string& path, const NiftiHeaderBytes& b, NiftiHeader& h) {
    const double slope = b.f32(kOffSclSlope);
    const double intercept = b.f32(kOffSclInter);
    if (std::isnan(slope) || slope == 0.0) return;
    if (!std::isfinite(slope))
        throwIoError(path, "scl_slope is " + std::to_string(slope) + ", not a finite number");
    if (slope == 1.0 && intercept == 0.0) return;
    if (!std::isfinite(intercept))
        throwIoError(path, "scl_inter is " + std::to_string(intercept) + ", not a finite number");
    h.scaled = true;
    h.slope = slope;
    h.intercept = intercept;
}

// The qform's rotation (NIfTI-1 header docs, "METHOD 2"): the quaternion (b, c, d) with
// a = sqrt(1 - b^2 - c^2 - d^2), the third column negated when qfac = pixdim[0] is negative.
// Like nifti1_io, a quaternion longer than 1 is read as (0, b, c, d) normalised.
glm::dmat3 qformRotation(const std::string& path, const NiftiHeaderBytes& b) {
    double q[3];
    for (int k = 0; k < 3; ++k) {
        q[k] = b.f32(kOffQuatern + 4 * k);
        if (!std::isfinite(q[k]))
            throwIoError(path, "qform quaternion holds a value that is not finite");
    }
    double qb = q[0], qc = q[1], qd = q[2];
    const double norm2 = qb * qb + qc * qc + qd * qd;
    double qa = 1.0 - norm2;
    if (qa < 1e-7) {
        const double scale = 1.0 / std::sqrt(norm2);
        qb *= scale;
        qc *= scale;
        qd *= scale;
        qa = 0.0;
    } else {
        qa = std::sqrt(qa);
    }
    // R's columns (the header docs write R by rows); glm's matrices are indexed [column][row].
    glm::dmat3 r;
    r[0] = {qa * qa + qb * qb - qc * qc - qd * qd, 2 * (qb * qc + qa * qd), 2 * (qb * qd - qa * qc)};
    r[1] = {2 * (qb * qc - qa * qd), qa * qa + qc * qc - qb * qb - qd * qd, 2 * (qc * qd + qa * qb)};
    r[2] = {2 * (qb * qd + qa * qc), 2 * (qc * qd - qa * qb), qa * qa + qd * qd - qc * qc - qb * qb};
    const double qfac = b.f32(kOffPixdim) < 0.0f ? -1.0 : 1.0;
    r[2] *= qfac;
    return r;
}

// True when the matrix's columns are orthogonal (up to the rounding of a float header): a
// rotation, maybe mirrored, times a scale per axis, with no shear.
bool columnsOrthogonal(const glm::dmat3& m) {
    for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j)
            if (std::abs(glm::dot(glm::normalize(m[i]), glm::normalize(m[j]))) > 1e-4) return false;
    return true;
}

// Placement, as nibabel and ITK choose it: the sform when sform_code > 0, unless it shears and
// a qform is there too (ITK then takes the qform: a rigid placement); else the qform when
// qform_code > 0; else none: the volume sits axis-aligned at 0 with pixdim's spacing. (3D Slicer
// reads NIfTI through ITK, so its models and these meshes land in the same place.) NIfTI's
// space is RAS; ours is LPS. The sform's columns are the axes' whole steps, so they give the
// spacing too. Units (xyzt_units) are not read: the numbers are taken as they are.
void niftiPlacement(const std::string& path, const NiftiHeaderBytes& b, NiftiHeader& h) {
    const bool hasQform = b.i16(kOffQformCode) > 0, hasSform = b.i16(kOffSformCode) > 0;
    glm::dmat3 ras(1.0);
    glm::dvec3 rasOrigin(0.0);
    bool useSform = false;
    if (hasSform) {
        glm::dmat3 scaled;
        for (int row = 0; row < 3; ++row) {
            for (int c = 0; c < 3; ++c) scaled[c][row] = b.f32(kOffSrowX + kSrowStride * row + 4 * c);
            rasOrigin[row] = b.f32(kOffSrowX + kSrowStride * row + 12);
        }
        // A broken sform beside a qform is passed over, as ITK does; alone, it is refused.
        std::string problem = directionProblem(scaled);
        if (problem.empty() && !std::isfinite(rasOrigin.x + rasOrigin.y + rasOrigin.z))
            problem = "translation holds a value that is not finite";
        if (!problem.empty() && !hasQform) throwIoError(path, "sform: " + problem);
        useSform = problem.empty() && (!hasQform || columnsOrthogonal(scaled));
        if (useSform) splitScaledColumns(scaled, ras, h.spacing);
    }
    if (!useSform && hasQform) {
        ras = qformRotation(path, b);
        for (int a = 0; a < 3; ++a) rasOrigin[a] = b.f32(kOffQoffset + 4 * a);
        if (!std::isfinite(rasOrigin.x + rasOrigin.y + rasOrigin.z))
            throwIoError(path, "qoffset holds a value that is not finite");
    } else if (!useSform) {
        return;
    }
    h.direction = kRasToLps * ras;
    h.origin = kRasToLps * rasOrigin;
    h.hasOrientation = true;
}

NiftiHeader parseNiftiHeader(const std::string& path, const NiftiHeaderBytes& b) {
    NiftiHeader h;
    h.bigEndian = b.bigEndian;
    const char* magic = reinterpret_cast<const char*>(b.bytes + kOffMagic);
    if (std::memcmp(magic, "n+1", 4) == 0)
        h.singleFile = true;
    else if (std::memcmp(magic, "ni1", 4) == 0)
        h.singleFile = false;
    else
        throwIoError(path,
                     "not a NIfTI-1 file (magic is not 'n+1' or 'ni1'; plain Analyze 7.5 "
                     "headers are not supported)");
    h.dims = niftiDims(path, b);
    const int datatype = b.i16(kOffDatatype);
    const auto type = niftiDatatypeToFileScalar(datatype);
    if (!type)
        throwIoError(path, "unsupported NIfTI datatype " + std::to_string(datatype) + " (" +
                               niftiDatatypeName(datatype) + ")");
    h.type = *type;
    h.voxOffset = niftiVoxOffset(path, b, h.singleFile);
    for (int a = 0; a < 3; ++a) {
        const double s = std::abs(double(b.f32(kOffPixdim + 4 * (a + 1))));
        h.spacing[a] = std::isfinite(s) && s > 0.0 ? s : 1.0;
    }
    niftiPlacement(path, b, h);
    niftiScaling(path, b, h);
    return h;
}

// For uncompressed samples the file size is known, so a mismatch is reported before reading.
void checkUncompressedSize(const std::string& path, const NiftiHeader& h, uint64_t dataBytes) {
    const uint64_t need = h.voxOffset + dataBytes;
    const uint64_t have = fileSize(path);
    if (have == need) return;
    const std::string detail = " (dims " + dimsText(h.dims) + ", type " + fileScalarName(h.type) +
                               ", vox_offset " + std::to_string(h.voxOffset) + " need " +
                               std::to_string(need) + " bytes)";
    throwFileSizeMismatch(path, have, need, "its header's dimensions", detail);
}

}  // namespace

std::unique_ptr<SliceReader> openNiftiVolume(const std::string& path) {
    const std::string headerPath =
        isImageFileName(path) ? companionFile(path, ".img", ".hdr") : path;
    const NiftiHeader h = parseNiftiHeader(headerPath, readNiftiHeaderBytes(headerPath));
    const std::string imagePath =
        h.singleFile ? headerPath : companionFile(headerPath, ".hdr", ".img");

    VolumeInfo info;
    info.dims = h.dims;
    info.type = storeTypeFor(h.type, h.scaled);
    info.spacing = h.spacing;
    info.origin = h.origin;
    info.direction = h.direction;
    info.hasOrientation = h.hasOrientation;
    const uint64_t dataBytes = uint64_t(info.sampleCount()) * fileScalarSize(h.type);
    const StreamSliceDecoder decoder(h.type, h.bigEndian != hostIsBigEndian(), info.type, h.scaled,
                                     h.slope, h.intercept);

    if (hasGzipMagic(imagePath)) {
        auto in = openGzipStream(imagePath);
        in->skip(h.voxOffset);
        return openStreamSliceReader(path, info, std::move(in), decoder, true);
    }
    checkUncompressedSize(imagePath, h, dataBytes);
    return openStreamSliceReader(path, info, openFileStream(imagePath, h.voxOffset), decoder,
                                 false);
}

}  // namespace vdiso
