// A NRRD header (io/readers/nrrd_reader.h) parsed field by field: what each field says, checked as
// text (numbers, vectors, the type's and encoding's spellings teem accepts), not yet against
// the others (that is the reader's: sizes, dimension, space directions together).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "io/readers/sample_decode.h"

namespace vdiso {

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

// Reads the header of the .nrrd or .nhdr file at `path` up to its blank line (or the end of a
// detached header). Throws IoError naming the file, and the field, for what it cannot parse:
// not NRRD000X, a line neither "field: value" nor a comment, an unknown or malformed value, an
// unsupported encoding or a multi-file data list.
NrrdHeader parseNrrdHeader(const std::string& path);

}  // namespace vdiso
