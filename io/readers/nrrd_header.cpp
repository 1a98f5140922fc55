#include "io/readers/nrrd_header.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <fstream>
#include <string_view>

#include "core/interrupt.h"
#include "io/error.h"
#include "io/readers/header_text.h"

namespace vdiso {
namespace {

// Headers are a few kB; a longer line means we are reading sample bytes, not a header.
constexpr size_t kMaxHeaderLine = 1 << 16;

// Collapses runs of whitespace so "unsigned   short" and "unsigned short" read alike.
std::string normalizeWords(std::string_view s) {
    std::string out;
    for (std::string_view w : splitWords(s)) {
        if (!out.empty()) out += ' ';
        out += toLowerAscii(w);
    }
    return out;
}

template <class T>
std::optional<T> parseNumber(std::string_view s) {
    s = trimSpace(s);
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
            if (toLowerAscii(word) != "none")
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
        if (toLowerAscii(value) != "none") h.spaceOrigin = parseVector(path, field, value);
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

}  // namespace

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
                          readHeaderLine(path, in, line, consumed) && trimSpace(line).empty();
    if (!hasMagic) throwIoError(path, "not a NRRD file (the first line is not NRRD000X)");
    consumed += 8;
    while (readHeaderLine(path, in, line, consumed)) {
        if (trimSpace(line).empty()) {
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
        applyNrrdField(path, field, trimSpace(std::string_view(line).substr(colon + 1)), h);
    }
    h.headerBytes = consumed;
    return h;
}

}  // namespace vdiso
