#include "io/nrrd_reader.h"

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
#include "io/byte_stream.h"
#include "io/error.h"
#include "io/raw_reader.h"
#include "io/sample_decode.h"

namespace vdiso {
namespace {

enum class NrrdEncoding { Raw, Gzip };

// One entry of "space directions": a vector, or "none" for a non-spatial axis.
using NrrdDirection = std::optional<std::vector<double>>;

struct NrrdHeader {
    std::optional<int> dimension;
    std::optional<FileScalar> type;
    std::vector<int64_t> sizes;
    std::optional<NrrdEncoding> encoding;
    std::optional<bool> bigEndian;
    std::vector<double> spacings;
    std::vector<NrrdDirection> spaceDirections;
    std::optional<std::vector<double>> spaceOrigin;
    std::string space;  // the "space" field, lower case with single spaces; "" when absent
    int64_t byteSkip = 0;
    int64_t lineSkip = 0;
    std::string dataFile;      // empty when the data is attached
    uint64_t headerBytes = 0;  // where attached data starts
    bool endsWithBlankLine = false;
};

// Headers are a few kB; a longer line means we are reading sample bytes, not a header.
constexpr size_t kMaxHeaderLine = 1 << 16;

std::string_view trim(std::string_view s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    return s;
}

std::string toLower(std::string_view s) {
    std::string out(s);
    for (char& c : out) c = char(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

std::vector<std::string_view> splitWords(std::string_view s) {
    std::vector<std::string_view> words;
    size_t i = 0;
    while (i < s.size()) {
        while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
        size_t start = i;
        while (i < s.size() && !std::isspace(static_cast<unsigned char>(s[i]))) ++i;
        if (i > start) words.push_back(s.substr(start, i - start));
    }
    return words;
}

// Collapses runs of whitespace so "unsigned   short" and "unsigned short" read alike.
std::string normalizeWords(std::string_view s) {
    std::string out;
    for (std::string_view w : splitWords(s)) {
        if (!out.empty()) out += ' ';
        out += toLower(w);
    }
    return out;
}

template <class T>
std::optional<T> parseNumber(std::string_view s) {
    s = trim(s);
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    T value{};
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    if (ec != std::errc() || end != s.data() + s.size() || s.empty()) return std::nullopt;
    return value;
}

int64_t parseInteger(const std::string& path, std::string_view field, std::string_view text) {
    auto v = parseNumber<int64_t>(text);
    if (!v)
        throwIoError(path,
                     "'" + std::string(field) + "' is not an integer: '" + std::string(text) + "'");
    return *v;
}

std::vector<double> parseDoubles(const std::string& path, std::string_view field,
                                 std::string_view text) {
    std::vector<double> values;
    for (std::string_view w : splitWords(text)) {
        auto v = parseNumber<double>(w);
        if (!v)
            throwIoError(path, "'" + std::string(field) + "' holds '" + std::string(w) +
                                   "', which is not a number");
        values.push_back(*v);
    }
    return values;
}

// "(1,0,0)" or "( 1, 0, 0 )".
std::vector<double> parseVector(const std::string& path, std::string_view field,
                                std::string_view text) {
    if (text.size() < 2 || text.front() != '(' || text.back() != ')')
        throwIoError(path, "'" + std::string(field) + "' holds '" + std::string(text) +
                               "', which is not a vector like (1,0,0)");
    std::string inner(text.substr(1, text.size() - 2));
    std::replace(inner.begin(), inner.end(), ',', ' ');
    return parseDoubles(path, field, inner);
}

// "(1,0,0) (0,1,0) none": vectors and "none" separated by whitespace.
std::vector<NrrdDirection> parseDirections(const std::string& path, std::string_view field,
                                           std::string_view text) {
    std::vector<NrrdDirection> out;
    size_t i = 0;
    while (i < text.size()) {
        if (std::isspace(static_cast<unsigned char>(text[i]))) {
            ++i;
            continue;
        }
        size_t end;
        if (text[i] == '(') {
            end = text.find(')', i);
            if (end == std::string_view::npos)
                throwIoError(path, "'" + std::string(field) + "' has an unclosed '('");
            ++end;
            out.emplace_back(parseVector(path, field, text.substr(i, end - i)));
        } else {
            end = i;
            while (end < text.size() && !std::isspace(static_cast<unsigned char>(text[end]))) ++end;
            std::string_view word = text.substr(i, end - i);
            if (toLower(word) != "none")
                throwIoError(path, "'" + std::string(field) + "' holds '" + std::string(word) +
                                       "', which is neither a vector nor 'none'");
            out.emplace_back(std::nullopt);
        }
        i = end;
    }
    return out;
}

// Every spelling teem accepts (nrrdTypeStr and its aliases).
std::optional<FileScalar> nrrdTypeToFileScalar(const std::string& type) {
    static const std::pair<const char*, FileScalar> kTypes[] = {
        {"signed char", FileScalar::I8},
        {"int8", FileScalar::I8},
        {"int8_t", FileScalar::I8},
        {"uchar", FileScalar::U8},
        {"unsigned char", FileScalar::U8},
        {"uint8", FileScalar::U8},
        {"uint8_t", FileScalar::U8},
        {"short", FileScalar::I16},
        {"short int", FileScalar::I16},
        {"signed short", FileScalar::I16},
        {"signed short int", FileScalar::I16},
        {"int16", FileScalar::I16},
        {"int16_t", FileScalar::I16},
        {"ushort", FileScalar::U16},
        {"unsigned short", FileScalar::U16},
        {"unsigned short int", FileScalar::U16},
        {"uint16", FileScalar::U16},
        {"uint16_t", FileScalar::U16},
        {"int", FileScalar::I32},
        {"signed int", FileScalar::I32},
        {"int32", FileScalar::I32},
        {"int32_t", FileScalar::I32},
        {"uint", FileScalar::U32},
        {"unsigned int", FileScalar::U32},
        {"uint32", FileScalar::U32},
        {"uint32_t", FileScalar::U32},
        {"float", FileScalar::F32},
        {"double", FileScalar::F64},
    };
    for (const auto& [name, scalar] : kTypes)
        if (type == name) return scalar;
    return std::nullopt;
}

bool isNrrd64BitType(const std::string& type) {
    static const char* const kTypes[] = {
        "longlong", "long long", "long long int", "signed long long",   "signed long long int",
        "int64",    "int64_t",   "ulonglong",     "unsigned long long", "unsigned long long int",
        "uint64",   "uint64_t"};
    return std::find(std::begin(kTypes), std::end(kTypes), type) != std::end(kTypes);
}

FileScalar parseNrrdType(const std::string& path, std::string_view value) {
    const std::string type = normalizeWords(value);
    if (auto scalar = nrrdTypeToFileScalar(type)) return *scalar;
    if (isNrrd64BitType(type))
        throwIoError(path, "NRRD type '" + type +
                               "' is not supported: 64-bit integer samples do not fit the store");
    if (type == "block")
        throwIoError(path, "NRRD type 'block' is not supported: samples must be numbers");
    throwIoError(path, "unknown NRRD type '" + type + "'");
}

NrrdEncoding parseNrrdEncoding(const std::string& path, std::string_view value) {
    const std::string encoding = normalizeWords(value);
    if (encoding == "raw") return NrrdEncoding::Raw;
    if (encoding == "gzip" || encoding == "gz") return NrrdEncoding::Gzip;
    // ascii/text/txt, hex and bzip2/bz2 are valid NRRD but rare for volumes of this size.
    throwIoError(path,
                 "unsupported NRRD encoding '" + encoding + "' (only raw and gzip are supported)");
}

bool parseNrrdEndian(const std::string& path, std::string_view value) {
    const std::string endian = normalizeWords(value);
    if (endian == "little") return false;
    if (endian == "big") return true;
    throwIoError(path, "unknown NRRD endian '" + endian + "' (expected little or big)");
}

// "data file: name", "data file: LIST" (names on the lines that follow) or the printf-style
// "data file: name%03d.raw <min> <max> <step> [<subdim>]".
std::string parseDataFile(const std::string& path, std::string_view value) {
    const std::vector<std::string_view> words = splitWords(value);
    if (words.empty()) throwIoError(path, "'data file' names no file");
    // A file name cannot hold a NUL byte; the C library would open what precedes it.
    if (value.find('\0') != std::string_view::npos)
        throwIoError(path, "'data file' name holds a NUL byte");
    if (words[0] == "LIST")
        throwIoError(path, "multi-file NRRD data ('data file: LIST') is not supported");
    const bool isFormatForm = words.size() >= 4 && words[0].find('%') != std::string_view::npos &&
                              parseNumber<int64_t>(words[1]) && parseNumber<int64_t>(words[2]) &&
                              parseNumber<int64_t>(words[3]);
    if (isFormatForm)
        throwIoError(path, "multi-file NRRD data ('data file: " + std::string(words[0]) +
                               " <min> <max> <step>') is not supported");
    return std::string(value);
}

void applyNrrdField(const std::string& path, const std::string& field, std::string_view value,
                    NrrdHeader& h) {
    if (field == "dimension") {
        h.dimension = int(parseInteger(path, field, value));
    } else if (field == "type") {
        h.type = parseNrrdType(path, value);
    } else if (field == "sizes") {
        h.sizes.clear();
        for (std::string_view w : splitWords(value))
            h.sizes.push_back(parseInteger(path, field, w));
    } else if (field == "encoding") {
        h.encoding = parseNrrdEncoding(path, value);
    } else if (field == "endian") {
        h.bigEndian = parseNrrdEndian(path, value);
    } else if (field == "spacings") {
        h.spacings = parseDoubles(path, field, value);
    } else if (field == "space directions") {
        h.spaceDirections = parseDirections(path, field, value);
    } else if (field == "space") {
        h.space = normalizeWords(value);
    } else if (field == "space origin") {
        if (toLower(value) != "none") h.spaceOrigin = parseVector(path, field, value);
    } else if (field == "byte skip") {
        h.byteSkip = parseInteger(path, field, value);
    } else if (field == "line skip") {
        h.lineSkip = parseInteger(path, field, value);
    } else if (field == "data file" || field == "datafile") {
        h.dataFile = parseDataFile(path, value);
    }
    // Every other field (kinds, centers, content, ...) does not change the samples.
}

// Reads one '\n'-terminated line (a trailing '\r' dropped); false at end of file.
bool readHeaderLine(const std::string& path, std::istream& in, std::string& line,
                    uint64_t& consumed) {
    line.clear();
    std::streambuf* buf = in.rdbuf();
    for (;;) {
        const int c = buf->sbumpc();
        if (c == std::char_traits<char>::eof()) {
            if (line.empty()) return false;
            break;
        }
        ++consumed;
        if ((consumed & 0xfffff) == 0) throwIfInterrupted(path);  // endless headers
        if (c == '\n') break;
        line += char(c);
        if (line.size() > kMaxHeaderLine)
            throwIoError(path, "header line longer than " + std::to_string(kMaxHeaderLine) +
                                   " bytes: is the blank line that ends the header missing?");
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
}

NrrdHeader parseNrrdHeader(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throwSystemError(path, "cannot open", errno);
    NrrdHeader h;
    std::string line;
    uint64_t consumed = 0;
    // The magic is checked before reading lines, so a binary file gets "not a NRRD file".
    char magic[8] = {};
    in.read(magic, 8);
    const bool hasMagic = std::string_view(magic, 7) == "NRRD000" &&
                          std::isdigit(static_cast<unsigned char>(magic[7])) && in.gcount() == 8 &&
                          readHeaderLine(path, in, line, consumed) && trim(line).empty();
    if (!hasMagic) throwIoError(path, "not a NRRD file (the first line is not NRRD000X)");
    consumed += 8;
    while (readHeaderLine(path, in, line, consumed)) {
        if (trim(line).empty()) {
            h.endsWithBlankLine = true;
            break;
        }
        if (line[0] == '#') continue;
        const size_t colon = line.find(':');
        if (colon == std::string::npos)
            throwIoError(path,
                         "header line '" + line + "' is neither 'field: value' nor a comment");
        if (colon + 1 < line.size() && line[colon + 1] == '=') continue;  // key:=value
        const std::string field = normalizeWords(std::string_view(line).substr(0, colon));
        applyNrrdField(path, field, trim(std::string_view(line).substr(colon + 1)), h);
    }
    h.headerBytes = consumed;
    return h;
}

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
