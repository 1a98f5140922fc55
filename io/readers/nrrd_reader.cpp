#include "io/readers/nrrd_reader.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>
#include <vector>

#include "core/interrupt.h"
#include "core/orientation.h"
#include "io/readers/byte_stream.h"
#include "io/error.h"
#include "io/readers/nrrd_header.h"
#include "io/readers/raw_reader.h"
#include "io/readers/sample_decode.h"

namespace vdiso {
namespace {

void requireField(const std::string& path, bool present, const char* field) {
    if (!present) throwIoError(path, std::string("header has no '") + field + "' field");
}

// The index of the axis a 4-D header carries only for form (size 1, first or last), or -1.
int singletonAxisToDrop(const NrrdHeader& h) {
    if (*h.dimension != 4) return -1;
    if (h.sizes[0] == 1) return 0;
    if (h.sizes[3] == 1) return 3;
    return -1;
}

double axisSpacing(const NrrdHeader& h, int axis) {
    if (!h.spaceDirections.empty() && h.spaceDirections[axis]) {
        const std::vector<double>& d = *h.spaceDirections[axis];
        double norm2 = 0.0;
        for (double c : d) norm2 += c * c;
        const double norm = std::sqrt(norm2);
        if (std::isfinite(norm) && norm > 0.0) return norm;
    }
    if (!h.spacings.empty()) {
        const double s = std::abs(h.spacings[axis]);
        if (std::isfinite(s) && s > 0.0) return s;
    }
    return 1.0;
}

std::string sizesText(const Dims3& dims) {
    return std::to_string(dims[0]) + " " + std::to_string(dims[1]) + " " + std::to_string(dims[2]);
}

// The "space" field's map to LPS (NRRD spec, "space"), or nullopt for a space without patient
// directions (scanner-xyz, 3D-right-handed, ...) or none given: the grid is then placed by the
// space directions' lengths and the space origin, without orientation. Unknown names are
// refused, as teem refuses them.
std::optional<glm::dmat3> spaceToLps(const std::string& path, const std::string& space) {
    if (space.empty()) return std::nullopt;
    static const char* const kUnoriented[] = {"scanner-xyz", "scanner-xyz-time", "3d-right-handed",
                                              "3d-left-handed", "3d-right-handed-time",
                                              "3d-left-handed-time"};
    for (const char* name : kUnoriented)
        if (space == name) return std::nullopt;
    const glm::dmat3 las{1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0};
    const std::pair<const char*, glm::dmat3> kAnatomical[] = {
        {"right-anterior-superior", kRasToLps}, {"ras", kRasToLps},
        {"right-anterior-superior-time", kRasToLps}, {"rast", kRasToLps},
        {"left-anterior-superior", las}, {"las", las},
        {"left-anterior-superior-time", las}, {"last", las},
        {"left-posterior-superior", glm::dmat3(1.0)}, {"lps", glm::dmat3(1.0)},
        {"left-posterior-superior-time", glm::dmat3(1.0)}, {"lpst", glm::dmat3(1.0)},
    };
    for (const auto& [name, toLps] : kAnatomical)
        if (space == name) return toLps;
    throwIoError(path, "unknown NRRD space '" + space +
                           "' (expected right-anterior-superior, left-anterior-superior, "
                           "left-posterior-superior, scanner-xyz, 3D-right-handed or "
                           "3D-left-handed, or their short and -time forms)");
}

// Orientation from "space" and the kept axes' "space directions" (the columns, direction times
// spacing); the origin follows the same map. Without an anatomical space or with a non-spatial
// axis, none: the origin as given.
void nrrdPlacement(const std::string& path, const NrrdHeader& h, int dropAxis, VolumeInfo& info) {
    const std::optional<glm::dmat3> toLps = spaceToLps(path, h.space);
    glm::dvec3 origin(0.0);
    if (h.spaceOrigin) {
        const std::vector<double>& o = *h.spaceOrigin;
        if (toLps && o.size() != 3)
            throwIoError(path, "'space origin' has " + std::to_string(o.size()) +
                                   " components; space " + h.space + " has 3");
        for (int a = 0; a < 3 && a < int(o.size()); ++a) {
            if (toLps && !std::isfinite(o[a]))
                throwIoError(path, "'space origin' holds a value that is not finite");
            origin[a] = std::isfinite(o[a]) ? o[a] : 0.0;
        }
    }
    glm::dmat3 scaled(1.0);
    bool spatial = !h.spaceDirections.empty();
    int column = 0;
    for (int axis = 0; spatial && axis < int(h.spaceDirections.size()); ++axis) {
        if (axis == dropAxis) continue;
        const NrrdDirection& d = h.spaceDirections[axis];
        if (!d) {
            spatial = false;
            break;
        }
        if (d->size() != 3) {
            if (toLps)
                throwIoError(path, "'space directions' has a vector of " + std::to_string(d->size()) +
                                       " components; space " + h.space + " has 3");
            spatial = false;
            break;
        }
        scaled[column++] = {(*d)[0], (*d)[1], (*d)[2]};
    }
    if (toLps && spatial) {
        if (const std::string problem = directionProblem(scaled); !problem.empty())
            throwIoError(path, "'space directions': " + problem);
        glm::dvec3 spacing;
        splitScaledColumns(scaled, info.direction, spacing);
        info.direction = *toLps * info.direction;
        info.hasOrientation = true;
        origin = *toLps * origin;
    }
    info.origin = origin;
}

// Checks the header describes a scalar 3-D volume and turns it into VolumeInfo.
VolumeInfo nrrdVolumeInfo(const std::string& path, const NrrdHeader& h) {
    requireField(path, h.dimension.has_value(), "dimension");
    requireField(path, h.type.has_value(), "type");
    requireField(path, !h.sizes.empty(), "sizes");
    requireField(path, h.encoding.has_value(), "encoding");
    const int dimension = *h.dimension;
    if (int(h.sizes.size()) != dimension)
        throwIoError(path, "'sizes' has " + std::to_string(h.sizes.size()) +
                               " entries but 'dimension' is " + std::to_string(dimension));
    const int dropAxis = singletonAxisToDrop(h);
    if (dimension != 3 && dropAxis < 0)
        throwIoError(path, "dimension " + std::to_string(dimension) +
                               ": only scalar 3-D volumes are supported");
    if (!h.spacings.empty() && int(h.spacings.size()) != dimension)
        throwIoError(path, "'spacings' has " + std::to_string(h.spacings.size()) +
                               " entries but 'dimension' is " + std::to_string(dimension));
    if (!h.spaceDirections.empty() && int(h.spaceDirections.size()) != dimension)
        throwIoError(path, "'space directions' has " + std::to_string(h.spaceDirections.size()) +
                               " entries but 'dimension' is " + std::to_string(dimension));
    if (fileScalarSize(*h.type) > 1 && !h.bigEndian)
        throwIoError(path, "header has no 'endian' field, which multi-byte samples need");
    if (h.byteSkip < -1) throwIoError(path, "byte skip " + std::to_string(h.byteSkip) + " < -1");
    if (h.lineSkip < 0) throwIoError(path, "line skip " + std::to_string(h.lineSkip) + " < 0");

    VolumeInfo info;
    info.type = storeTypeFor(*h.type, false);
    int out = 0;
    for (int axis = 0; axis < dimension; ++axis) {
        if (axis == dropAxis) continue;
        info.dims[out] = h.sizes[axis];
        info.spacing[out] = axisSpacing(h, axis);
        ++out;
    }
    for (int64_t d : info.dims)
        if (d < 2)
            throwIoError(path,
                         "sizes " + sizesText(info.dims) + ": every axis needs at least 2 samples");
    requireVolumeDims(path, info.dims);
    // Bounds the byte count below 2^62, so later arithmetic cannot overflow.
    double bytes = double(fileScalarSize(*h.type));
    for (int64_t d : info.dims) bytes *= double(d);
    if (bytes > 0x1p62) throwIoError(path, "sizes " + sizesText(info.dims) + " are too large");
    nrrdPlacement(path, h, dropAxis, info);
    return info;
}

std::string resolveDataFile(const std::string& headerPath, const std::string& dataFile) {
    std::filesystem::path p(dataFile);
    if (p.is_absolute()) return p.string();
    return (std::filesystem::path(headerPath).parent_path() / p).string();
}

// The offset just past `lines` lines starting at `offset`.
uint64_t skipLines(const std::string& path, uint64_t offset, int64_t lines) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throwSystemError(path, "cannot open", errno);
    in.seekg(std::streamoff(offset));
    std::streambuf* buf = in.rdbuf();
    for (int64_t l = 0; l < lines; ++l) {
        for (;;) {
            const int c = buf->sbumpc();
            if (c == std::char_traits<char>::eof())
                throwIoError(path, "ends within the " + std::to_string(lines) +
                                       " lines the header's 'line skip' skips");
            ++offset;
            // Lines may be many, long or endless (a data file of /dev/zero): yield to Ctrl-C
            // every MiB.
            if ((offset & 0xfffff) == 0) throwIfInterrupted(path);
            if (c == '\n') break;
        }
    }
    return offset;
}

// For raw encoding the file size is known up front, so a mismatch is reported before reading.
uint64_t rawDataOffset(const std::string& dataPath, const std::string& headerPath, uint64_t start,
                       int64_t byteSkip, uint64_t dataBytes, const Dims3& dims, FileScalar type) {
    const uint64_t have = fileSize(dataPath);
    const uint64_t offset =
        byteSkip == -1 ? (have >= dataBytes ? have - dataBytes : start) : start + byteSkip;
    const uint64_t need = offset + dataBytes;
    if (have == need && offset >= start) return offset;
    const std::string whose =
        dataPath == headerPath ? "its header's sizes" : "the sizes in " + headerPath;
    const std::string detail = " (sizes " + sizesText(dims) + ", type " + fileScalarName(type) +
                               ", data from byte " + std::to_string(offset) + " needs " +
                               std::to_string(need) + " bytes)";
    // With byte skip -1 the data must fit between `start` and the end of the file.
    if (byteSkip == -1) throwFileSizeMismatch(dataPath, have, start + dataBytes, whose, detail);
    throwFileSizeMismatch(dataPath, have, need, whose, detail);
}

}  // namespace

std::unique_ptr<SliceReader> openNrrdVolume(const std::string& path) {
    const NrrdHeader h = parseNrrdHeader(path);
    const VolumeInfo info = nrrdVolumeInfo(path, h);
    const bool attached = h.dataFile.empty();
    if (attached && !h.endsWithBlankLine)
        throwIoError(path,
                     "has no data: the header neither ends with a blank line nor names a "
                     "'data file'");
    const std::string dataPath = attached ? path : resolveDataFile(path, h.dataFile);
    std::error_code ec;
    if (!attached && std::filesystem::is_directory(dataPath, ec))
        throwIoError(path, "its data file " + dataPath + " is a directory, not a file of samples");
    uint64_t start = attached ? h.headerBytes : 0;
    if (h.lineSkip > 0) start = skipLines(dataPath, start, h.lineSkip);

    const FileScalar fileType = *h.type;
    const bool swapBytes = h.bigEndian.value_or(false) != hostIsBigEndian();
    const uint64_t dataBytes = uint64_t(info.sampleCount()) * fileScalarSize(fileType);
    const StreamSliceDecoder decoder(fileType, swapBytes, info.type, false, 1.0, 0.0);
    if (*h.encoding == NrrdEncoding::Raw) {
        const uint64_t offset =
            rawDataOffset(dataPath, path, start, h.byteSkip, dataBytes, info.dims, fileType);
        return openStreamSliceReader(path, info, openFileStream(dataPath, offset), decoder, false);
    }
    if (h.byteSkip == -1)
        throwIoError(path,
                     "byte skip -1 (data at the end of the file) needs raw encoding, "
                     "not gzip");
    auto in = openGzipStream(dataPath, start);
    // With gzip, byte skip counts decompressed bytes (as teem reads it).
    in->skip(uint64_t(h.byteSkip));
    return openStreamSliceReader(path, info, std::move(in), decoder, true);
}

}  // namespace vdiso
