// Helpers shared by the NRRD and NIfTI reader tests: a small test volume whose values every
// file type holds exactly, encoding it as files store it, gzip, and a fixture that writes the
// files into a scratch directory.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include "io/readers/sample_decode.h"
#include "io/readers/slice_reader.h"
#include "tests/test_util.h"

namespace vdiso::test {

// The shape of every test volume: small, and uneven so a swapped axis shows.
constexpr Dims3 kDims{7, 5, 4};
constexpr int64_t kSamples = 7 * 5 * 4;

// kSamples distinct values that `type` holds exactly, also after conversion to its store type.
std::vector<double> testValues(FileScalar type);

// kSamples u16 values that compress poorly, so their deflate stream has a middle to corrupt.
std::vector<double> incompressibleU16Values();

// `values` as `type` samples in the given byte order, as a file stores them.
std::string encodeSamples(const std::vector<double>& values, FileScalar type, bool bigEndian);

// `data` in a gzip wrapper, as teem, ITK and nibabel write it.
std::string gzipBytes(const std::string& data);

// Every sample the reader delivers, as doubles, after finish(). Reads in slabs of 3 slices, so
// the 4 slices of kDims take a multi-slice slab and then a short one.
std::vector<double> readAllValues(SliceReader& reader);

// Reads everything and checks it sample by sample against `want`.
void expectValues(SliceReader& reader, const std::vector<double>& want);

// SliceReader::skip against reading: for every k from 0 to the depth, a fresh reader from
// `open` that skips k slices (in two steps when it can) and reads the rest delivers the bytes a
// reader that reads everything delivers from slice k on, and then finishes without complaint;
// skipping past the end throws IoError.
void expectSkipMatchesRead(const std::function<std::unique_ptr<SliceReader>()>& open);

// EXPECT_DOUBLE_EQ per axis: spacings computed as vector lengths may be off in the last bit.
void expectDoubleEq(const glm::dvec3& got, const glm::dvec3& want);

// Every entry of a direction matrix within `tolerance` (columns: the axes' LPS directions).
void expectDirection(const glm::dmat3& got, const glm::dmat3& want, double tolerance = 1e-6);

// Expects `f` to throw IoError with a message containing every one of `parts`.
void expectIoError(const std::function<void()>& f, std::initializer_list<std::string> parts);

// Writes `bytes` as the store `path`, opens it and reads every brick: the IoError message that
// gives, or "" if none. Any other exception is a test failure (every refusal names the file).
std::string storeOpenError(const std::string& path, const std::vector<unsigned char>& bytes);

// A test that writes its input files into a fresh scratch directory.
class ReaderFileTest : public ::testing::Test {
protected:
    std::string path(const std::string& name) const { return mDir.file(name); }

    // Writes `bytes` to `name` (creating its directories) and returns the file's path.
    std::string write(const std::string& name, const std::string& bytes) const {
        const std::string p = path(name);
        std::filesystem::create_directories(std::filesystem::path(p).parent_path());
        writeFile(p, bytes);
        return p;
    }

private:
    ScratchDir mDir;
};

}  // namespace vdiso::test
