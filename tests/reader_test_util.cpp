#include "tests/reader_test_util.h"

#include <zlib.h>

#include <algorithm>
#include <cstring>

#include "io/store/brick_store.h"
#include "io/error.h"
#include "tests/test_util.h"

namespace vdiso::test {

namespace {

double sampleValue(FileScalar type, int64_t i) {
    switch (type) {
        case FileScalar::I8:
            return double(i - 70);
        case FileScalar::U8:
            return double(i + 100);
        case FileScalar::I16:
            return double(i * 37 - 2000);
        case FileScalar::U16:
            return double(60000 - i * 3);
        case FileScalar::I32:
            return double(i * 100000 - 7000000);
        case FileScalar::U32:
            return double(i * 1000 + 7);
        case FileScalar::F32:
            return double(i) * 0.25 - 3.0;
        case FileScalar::F64:
            return double(i) * 0.5 + 0.125;
    }
    return 0.0;
}

template <class T>
void appendScalar(std::string& out, double v, bool bigEndian) {
    const T x = T(v);
    unsigned char b[sizeof(T)];
    std::memcpy(b, &x, sizeof(T));
    if (bigEndian != hostIsBigEndian()) std::reverse(b, b + sizeof(T));
    out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

void appendSample(std::string& out, double v, FileScalar type, bool bigEndian) {
    switch (type) {
        case FileScalar::I8:
            return appendScalar<int8_t>(out, v, bigEndian);
        case FileScalar::U8:
            return appendScalar<uint8_t>(out, v, bigEndian);
        case FileScalar::I16:
            return appendScalar<int16_t>(out, v, bigEndian);
        case FileScalar::U16:
            return appendScalar<uint16_t>(out, v, bigEndian);
        case FileScalar::I32:
            return appendScalar<int32_t>(out, v, bigEndian);
        case FileScalar::U32:
            return appendScalar<uint32_t>(out, v, bigEndian);
        case FileScalar::F32:
            return appendScalar<float>(out, v, bigEndian);
        case FileScalar::F64:
            return appendScalar<double>(out, v, bigEndian);
    }
}

}  // namespace

std::vector<double> testValues(FileScalar type) {
    std::vector<double> v(kSamples);
    for (int64_t i = 0; i < kSamples; ++i) v[size_t(i)] = sampleValue(type, i);
    return v;
}

std::vector<double> incompressibleU16Values() {
    std::vector<double> v(kSamples);
    for (int64_t i = 0; i < kSamples; ++i) v[size_t(i)] = double((i * 7919) % 65536);
    return v;
}

std::string encodeSamples(const std::vector<double>& values, FileScalar type, bool bigEndian) {
    std::string out;
    for (double v : values) appendSample(out, v, type, bigEndian);
    return out;
}

std::string gzipBytes(const std::string& data) {
    z_stream z{};
    // 15 + 16: a gzip wrapper rather than a bare zlib stream.
    if (deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) return {};
    std::string out(deflateBound(&z, uLong(data.size())) + 32, '\0');
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
    z.avail_in = uInt(data.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = uInt(out.size());
    const int rc = deflate(&z, Z_FINISH);
    out.resize(z.total_out);
    deflateEnd(&z);
    return rc == Z_STREAM_END ? out : std::string();
}

std::vector<double> readAllValues(SliceReader& reader) {
    const ScalarType type = reader.info().type;
    const std::vector<unsigned char> bytes = readAllSamples(reader, 3);
    return visitScalarType(type, [&](auto zero) {
        using T = decltype(zero);
        const T* p = reinterpret_cast<const T*>(bytes.data());
        return std::vector<double>(p, p + bytes.size() / sizeof(T));
    });
}

void expectValues(SliceReader& reader, const std::vector<double>& want) {
    const std::vector<double> got = readAllValues(reader);
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < want.size(); ++i) ASSERT_EQ(got[i], want[i]) << "sample " << i;
}

void expectSkipMatchesRead(const std::function<std::unique_ptr<SliceReader>()>& open) {
    std::vector<unsigned char> all;
    int64_t depth = 0;
    size_t sliceBytes = 0;
    {
        auto whole = open();
        depth = whole->info().dims[2];
        sliceBytes = size_t(whole->info().sliceSamples()) * scalarSize(whole->info().type);
        all = readAllSamples(*whole, 3);
        ASSERT_EQ(all.size(), size_t(depth) * sliceBytes);
    }
    for (int64_t k = 0; k <= depth; ++k) {
        SCOPED_TRACE("skip " + std::to_string(k));
        auto reader = open();
        reader->skip(k / 2);
        reader->skip(k - k / 2);
        std::vector<unsigned char> rest(size_t(depth - k) * sliceBytes);
        if (k < depth) reader->read(rest.data(), depth - k);
        ASSERT_TRUE(std::equal(rest.begin(), rest.end(), all.begin() + ptrdiff_t(size_t(k) * sliceBytes)));
        EXPECT_NO_THROW(reader->finish());
    }
    auto reader = open();
    EXPECT_THROW(reader->skip(depth + 1), IoError);
}

void expectDoubleEq(const glm::dvec3& got, const glm::dvec3& want) {
    for (int a = 0; a < 3; ++a)
        EXPECT_DOUBLE_EQ(got[a], want[a]) << "axis "
                                          << "xyz"[a];
}

void expectDirection(const glm::dmat3& got, const glm::dmat3& want, double tolerance) {
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
            EXPECT_NEAR(got[c][r], want[c][r], tolerance) << "axis " << c << ", LPS component " << r;
}

void expectIoError(const std::function<void()>& f, std::initializer_list<std::string> parts) {
    try {
        f();
        ADD_FAILURE() << "expected an IoError";
    } catch (const IoError& e) {
        const std::string what = e.what();
        for (const std::string& part : parts)
            EXPECT_NE(what.find(part), std::string::npos)
                << "message '" << what << "' lacks '" << part << "'";
    }
}

std::string storeOpenError(const std::string& path, const std::vector<unsigned char>& bytes) {
    writeFile(path, bytes.data(), bytes.size());
    try {
        BrickStoreReader store(path);
        store.subBlockCodes();  // every part of the index (the sub-block codes are read as asked for)
        std::vector<unsigned char> brick(store.brickBytes());
        for (int64_t id = 0; id < store.layout().brickCount(); ++id) store.readBrick(id, brick.data());
    } catch (const IoError& e) {
        return e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "not an IoError: " << e.what();
        return e.what();
    }
    return "";
}

}  // namespace vdiso::test
