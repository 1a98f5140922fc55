#include "io/readers/metaimage_reader.h"

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>
#include <vector>

#include "core/orientation.h"
#include "io/readers/byte_stream.h"
#include "io/error.h"
#include "io/readers/header_text.h"
#include "io/readers/raw_reader.h"
#include "io/readers/sample_decode.h"

namespace vdiso {
namespace {

// A header is a few hundred bytes; one that runs on this long is not a MetaImage header.
constexpr uint64_t kMaxHeaderBytes = 1 << 20;

struct MetaHeader {
    std::optional<int> nDims;
    std::vector<int64_t> dimSize;
    std::optional<FileScalar> type;
    std::vector<double> spacing, offset;
    std::vector<double> transform;  // TransformMatrix (or Rotation, Orientation): NDims^2 values
    bool bigEndian = false;
    bool compressed = false;
    std::optional<uint64_t> compressedSize;
    int64_t headerSize = 0;
    std::string dataFile;  // "LOCAL" or a file name
    uint64_t headerBytes = 0;  // where LOCAL data starts
};

template <class T>
std::vector<T> numbers(const std::string& path, const std::string& key, std::string_view value) {
    std::vector<T> out;
    for (std::string_view w : splitWords(value)) {
        T v{};
        const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
        if (ec != std::errc() || end != w.data() + w.size())
            throwIoError(path, "'" + key + "' holds '" + std::string(w) + "', which is not a number");
        out.push_back(v);
    }
    return out;
}

template <class T>
T number(const std::string& path, const std::string& key, std::string_view value) {
    const std::vector<T> v = numbers<T>(path, key, value);
    if (v.size() != 1) throwIoError(path, "'" + key + "' should hold one number, not '" + std::string(value) + "'");
    return v[0];
}

bool boolean(const std::string& path, const std::string& key, std::string_view value) {
    const std::string v = toLowerAscii(trimSpace(value));
    if (v == "true" || v == "1") return true;
    if (v == "false" || v == "0") return false;
    throwIoError(path, "'" + key + "' should be True or False, not '" + std::string(value) + "'");
}

FileScalar elementType(const std::string& path, std::string_view value) {
    static const std::pair<const char*, FileScalar> kTypes[] = {
        {"MET_CHAR", FileScalar::I8},   {"MET_UCHAR", FileScalar::U8},
        {"MET_SHORT", FileScalar::I16}, {"MET_USHORT", FileScalar::U16},
        {"MET_INT", FileScalar::I32},   {"MET_UINT", FileScalar::U32},
        {"MET_LONG", FileScalar::I32},  {"MET_ULONG", FileScalar::U32},  // 4 bytes in MetaIO
        {"MET_FLOAT", FileScalar::F32}, {"MET_DOUBLE", FileScalar::F64},
    };
    const std::string type(trimSpace(value));
    for (const auto& [name, scalar] : kTypes)
        if (type == name) return scalar;
    if (type.find("LONG_LONG") != std::string::npos)
        throwIoError(path, "ElementType " + type + " is not supported: 64-bit integer samples do "
                           "not fit the store");
    if (type.find("_ARRAY") != std::string::npos)
        throwIoError(path, "ElementType " + type + " is not supported: only scalar samples");
    throwIoError(path, "unknown ElementType '" + type + "'");
}

// Reads the header up to and including ElementDataFile, which must be its last field.
MetaHeader parseHeader(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throwSystemError(path, "cannot open", errno);
    MetaHeader h;
    std::string line;
    uint64_t consumed = 0;
    bool sawObjectType = false;
    while (true) {
        line.clear();
        std::streambuf* buf = in.rdbuf();
        bool ended = false;
        for (;;) {
            const int c = buf->sbumpc();
            if (c == std::char_traits<char>::eof()) {
                ended = true;
                break;
            }
            if (++consumed > kMaxHeaderBytes)
                throwIoError(path, "no ElementDataFile field in its first " +
                                       std::to_string(kMaxHeaderBytes) + " bytes: not a MetaImage header");
            if (c == '\n') break;
            if (c == '\0') throwIoError(path, "header holds a NUL byte: not a MetaImage header");
            line += char(c);
        }
        const std::string_view text = trimSpace(line);
        if (!text.empty()) {
            const size_t eq = text.find('=');
            if (eq == std::string_view::npos)
                throwIoError(path, "header line '" + std::string(text.substr(0, 80)) +
                                       "' is not 'Key = Value'");
            const std::string key(trimSpace(text.substr(0, eq)));
            const std::string_view value = trimSpace(text.substr(eq + 1));
            const std::string k = toLowerAscii(key);
            if (k == "objecttype") {
                sawObjectType = true;
                if (toLowerAscii(value) != "image")
                    throwIoError(path, "ObjectType is '" + std::string(value) + "', not Image");
            } else if (k == "ndims") {
                h.nDims = number<int>(path, key, value);
            } else if (k == "dimsize") {
                h.dimSize = numbers<int64_t>(path, key, value);
            } else if (k == "elementtype") {
                h.type = elementType(path, value);
            } else if (k == "elementnumberofchannels") {
                if (number<int64_t>(path, key, value) != 1)
                    throwIoError(path, "ElementNumberOfChannels " + std::string(value) +
                                           ": only single-channel images are supported");
            } else if (k == "elementspacing" || (k == "elementsize" && h.spacing.empty())) {
                h.spacing = numbers<double>(path, key, value);
            } else if (k == "offset" || ((k == "origin" || k == "position") && h.offset.empty())) {
                h.offset = numbers<double>(path, key, value);
            } else if (k == "transformmatrix" ||
                       ((k == "rotation" || k == "orientation") && h.transform.empty())) {
                h.transform = numbers<double>(path, key, value);
            } else if (k == "binarydatabyteordermsb" || k == "elementbyteordermsb") {
                h.bigEndian = boolean(path, key, value);
            } else if (k == "binarydata") {
                if (!boolean(path, key, value))
                    throwIoError(path, "BinaryData = False (ASCII samples) is not supported");
            } else if (k == "compresseddata") {
                h.compressed = boolean(path, key, value);
            } else if (k == "compresseddatasize") {
                const int64_t size = number<int64_t>(path, key, value);
                if (size < 0) throwIoError(path, "CompressedDataSize " + std::string(value) + " < 0");
                h.compressedSize = uint64_t(size);
            } else if (k == "headersize") {
                h.headerSize = number<int64_t>(path, key, value);
            } else if (k == "elementdatafile") {
                h.dataFile = std::string(value);
                h.headerBytes = consumed;
                break;
            }
        }
        if (ended) throwIoError(path, "header ends without an ElementDataFile field");
    }
    if (!sawObjectType && h.dimSize.empty()) throwIoError(path, "not a MetaImage header");
    return h;
}

std::string dimsText(const Dims3& d) {
    return std::to_string(d[0]) + " " + std::to_string(d[1]) + " " + std::to_string(d[2]);
}

VolumeInfo volumeInfo(const std::string& path, const MetaHeader& h) {
    if (!h.nDims) throwIoError(path, "header has no NDims field");
    if (!h.type) throwIoError(path, "header has no ElementType field");
    const int n = *h.nDims;
    if (int(h.dimSize.size()) != n)
        throwIoError(path, "DimSize has " + std::to_string(h.dimSize.size()) +
                               " entries but NDims is " + std::to_string(n));
    if (n != 3 && !(n == 4 && h.dimSize[3] == 1))
        throwIoError(path, "NDims " + std::to_string(n) + ": only 3-D volumes are supported");
    VolumeInfo info;
    for (int a = 0; a < 3; ++a) info.dims[a] = h.dimSize[size_t(a)];
    requireVolumeDims(path, info.dims);
    info.type = storeTypeFor(*h.type, false);
    for (int a = 0; a < 3 && a < int(h.spacing.size()); ++a)
        if (std::isfinite(h.spacing[size_t(a)]) && h.spacing[size_t(a)] != 0.0)
            info.spacing[a] = std::abs(h.spacing[size_t(a)]);
    for (int a = 0; a < 3 && a < int(h.offset.size()); ++a)
        if (std::isfinite(h.offset[size_t(a)])) info.origin[a] = h.offset[size_t(a)];
    if (!h.transform.empty()) {
        // As ITK's MetaImageIO reads it: the values in groups of NDims, group a the direction
        // of axis a, in ITK's LPS (AnatomicalOrientation is a label that ITK does not apply).
        if (h.transform.size() != size_t(n) * size_t(n))
            throwIoError(path, "TransformMatrix has " + std::to_string(h.transform.size()) +
                                   " values; NDims " + std::to_string(n) + " needs " + std::to_string(n * n));
        glm::dmat3 direction;
        for (int a = 0; a < 3; ++a)
            for (int r = 0; r < 3; ++r) direction[a][r] = h.transform[size_t(a * n + r)];
        if (const std::string problem = directionProblem(direction); !problem.empty())
            throwIoError(path, "TransformMatrix: " + problem);
        for (int a = 0; a < 3 && a < int(h.offset.size()); ++a)
            if (!std::isfinite(h.offset[size_t(a)]))
                throwIoError(path, "Offset holds a value that is not finite");
        info.direction = normalizedColumns(direction);
        info.hasOrientation = true;
    }
    return info;
}

std::string dataPath(const std::string& path, const MetaHeader& h) {
    const std::vector<std::string_view> w = splitWords(h.dataFile);
    if (w.empty()) throwIoError(path, "ElementDataFile names no file");
    if (w[0] == "LOCAL") return path;
    if (w[0] == "LIST" || (w.size() >= 3 && w[0].find('%') != std::string_view::npos))
        throwIoError(path, "ElementDataFile '" + h.dataFile +
                               "': data split over several files is not supported");
    const std::filesystem::path p(h.dataFile);
    if (p.is_absolute()) return p.string();
    return (std::filesystem::path(path).parent_path() / p).string();
}

}  // namespace

std::unique_ptr<SliceReader> openMetaImageVolume(const std::string& path) {
    const MetaHeader h = parseHeader(path);
    const VolumeInfo info = volumeInfo(path, h);
    const std::string data = dataPath(path, h);
    const bool local = data == path;
    const FileScalar type = *h.type;
    const uint64_t dataBytes = checkedMul(uint64_t(info.sampleCount()), uint64_t(fileScalarSize(type)));
    uint64_t have = 0;
    try {
        have = fileSize(data);
    } catch (const IoError& e) {
        if (local) throw;
        throwIoError(path, std::string("its ElementDataFile: ") + e.what());
    }
    if (h.headerSize < -1) throwIoError(path, "HeaderSize " + std::to_string(h.headerSize) + " < -1");
    uint64_t start = local ? h.headerBytes : 0;
    const StreamSliceDecoder decoder(type, h.bigEndian != hostIsBigEndian(), info.type, false, 1.0, 0.0);
    const std::string detail = " (DimSize " + dimsText(info.dims) + ", " + fileScalarName(type) + ")";
    if (!h.compressed) {
        if (h.headerSize == -1) {
            if (have < dataBytes) throwFileSizeMismatch(data, have, dataBytes, "its header's DimSize", detail);
            start = have - dataBytes;
        } else {
            start = checkedAdd(start, uint64_t(h.headerSize));
        }
        const uint64_t need = checkedAdd(start, dataBytes);
        if (have != need) throwFileSizeMismatch(data, have, need, "its header's DimSize", detail);
        return openStreamSliceReader(path, info, openFileStream(data, start), decoder, false);
    }
    if (h.headerSize == -1)
        throwIoError(path, "HeaderSize -1 (data at the end of the file) needs uncompressed data");
    start = checkedAdd(start, uint64_t(h.headerSize));
    if (start > have) throwIoError(data, "ends before its compressed data starts");
    if (h.compressedSize && have - start != *h.compressedSize)
        throwFileSizeMismatch(data, have, checkedAdd(start, *h.compressedSize),
                              "its header's CompressedDataSize", "");
    return openStreamSliceReader(path, info, openGzipStream(data, start), decoder, true);
}

}  // namespace vdiso
