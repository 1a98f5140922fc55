// HDF5 reader: datasets written here with the HDF5 C library (contiguous and chunked, deflate
// and shuffle, every sample type, big-endian) read back sample for sample; the dataset found
// when only the file is named; element_size_um; and the paths it must refuse by name.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "io/store/brick_store.h"
#include "io/error.h"
#include "io/readers/hdf5_reader.h"
#include "io/readers/sample_decode.h"
#include "io/readers/volume_open.h"
#include "tests/reader_test_util.h"

namespace vdiso {
namespace {

using test::expectIoError;
using test::kDims;
using test::testValues;

hid_t fileTypeOf(FileScalar t, bool bigEndian) {
    switch (t) {
        case FileScalar::I8: return bigEndian ? H5T_STD_I8BE : H5T_STD_I8LE;
        case FileScalar::U8: return bigEndian ? H5T_STD_U8BE : H5T_STD_U8LE;
        case FileScalar::I16: return bigEndian ? H5T_STD_I16BE : H5T_STD_I16LE;
        case FileScalar::U16: return bigEndian ? H5T_STD_U16BE : H5T_STD_U16LE;
        case FileScalar::I32: return bigEndian ? H5T_STD_I32BE : H5T_STD_I32LE;
        case FileScalar::U32: return bigEndian ? H5T_STD_U32BE : H5T_STD_U32LE;
        case FileScalar::F32: return bigEndian ? H5T_IEEE_F32BE : H5T_IEEE_F32LE;
        case FileScalar::F64: break;
    }
    return bigEndian ? H5T_IEEE_F64BE : H5T_IEEE_F64LE;
}

struct DatasetSpec {
    std::string name = "/volume";
    std::vector<hsize_t> dims{4, 5, 7};  // z, y, x
    FileScalar type = FileScalar::U16;
    bool bigEndian = false;
    std::vector<hsize_t> chunk;  // empty: contiguous
    bool deflate = false, shuffle = false;
    std::vector<double> elementSizeUm;  // z, y, x
};

// Adds a dataset of `values` (C order) to the file, creating groups on the way.
void addDataset(hid_t file, const DatasetSpec& s, const std::vector<double>& values) {
    hid_t space = H5Screate_simple(int(s.dims.size()), s.dims.data(), nullptr);
    hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    if (!s.chunk.empty()) {
        H5Pset_chunk(dcpl, int(s.chunk.size()), s.chunk.data());
        if (s.shuffle) H5Pset_shuffle(dcpl);
        if (s.deflate) H5Pset_deflate(dcpl, 6);
    }
    hid_t d = H5Dcreate2(file, s.name.c_str(), fileTypeOf(s.type, s.bigEndian), space, lcpl, dcpl,
                         H5P_DEFAULT);
    ASSERT_GE(d, 0);
    if (!values.empty()) {
        ASSERT_GE(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
    }
    if (!s.elementSizeUm.empty()) {
        const hsize_t three = 3;
        hid_t aspace = H5Screate_simple(1, &three, nullptr);
        hid_t a = H5Acreate2(d, "element_size_um", H5T_IEEE_F32LE, aspace, H5P_DEFAULT, H5P_DEFAULT);
        H5Awrite(a, H5T_NATIVE_DOUBLE, s.elementSizeUm.data());
        H5Aclose(a);
        H5Sclose(aspace);
    }
    H5Dclose(d);
    H5Pclose(dcpl);
    H5Pclose(lcpl);
    H5Sclose(space);
}

class Hdf5Test : public test::ReaderFileTest {
protected:
    hid_t create(const std::string& name) {
        return H5Fcreate(path(name).c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    }
};
using Hdf5Reader = Hdf5Test;
using Hdf5Errors = Hdf5Test;

TEST(Hdf5Path, SplitsFileAndDataset) {
    using P = std::pair<std::string, std::string>;
    EXPECT_EQ(splitHdf5Path("a/b.h5:/g/d"), (P{"a/b.h5", "/g/d"}));
    EXPECT_EQ(splitHdf5Path("b.HDF5:/d"), (P{"b.HDF5", "/d"}));
    EXPECT_EQ(splitHdf5Path("b.h5"), (P{"b.h5", ""}));
    EXPECT_EQ(splitHdf5Path("c:/x.h5:/d"), (P{"c:/x.h5", "/d"}));
    EXPECT_EQ(splitHdf5Path("b.nrrd"), std::nullopt);
}

TEST_F(Hdf5Reader, EveryTypeContiguousChunkedAndBigEndian) {
    for (FileScalar type : {FileScalar::I8, FileScalar::U8, FileScalar::I16, FileScalar::U16,
                            FileScalar::I32, FileScalar::U32, FileScalar::F32, FileScalar::F64}) {
        SCOPED_TRACE(fileScalarName(type));
        hid_t f = create("v.h5");
        DatasetSpec contiguous;
        contiguous.type = type;
        addDataset(f, contiguous, testValues(type));
        DatasetSpec chunked = contiguous;
        chunked.name = "/g/chunked";
        chunked.chunk = {3, 2, 4};  // uneven: partial chunks on every axis
        chunked.deflate = chunked.shuffle = true;
        chunked.bigEndian = true;
        addDataset(f, chunked, testValues(type));
        H5Fclose(f);
        for (const char* dataset : {":/volume", ":/g/chunked"}) {
            SCOPED_TRACE(dataset);
            auto reader = openHdf5Volume(path("v.h5") + dataset);
            EXPECT_EQ(reader->info().dims, kDims);
            EXPECT_EQ(reader->info().type, storeTypeFor(type, false));
            EXPECT_EQ(reader->name(), path("v.h5") + dataset);
            test::expectValues(*reader, testValues(type));
        }
    }
}

TEST_F(Hdf5Reader, TheOnlyVolumeOfAFileAndElementSize) {
    hid_t f = create("one.h5");
    DatasetSpec v;
    v.name = "/exchange/data";
    v.elementSizeUm = {2.0, 0.5, 0.25};
    addDataset(f, v, testValues(FileScalar::U16));
    DatasetSpec flat;
    flat.name = "/exchange/theta";
    flat.dims = {7};
    flat.type = FileScalar::F32;
    addDataset(f, flat, std::vector<double>(7, 1.0));
    H5Fclose(f);
    EXPECT_EQ(detectInputFormat(path("one.h5"), {}), InputFormat::Hdf5);
    auto reader = openVolume(path("one.h5"), {});
    EXPECT_EQ(reader->name(), path("one.h5") + ":/exchange/data");
    test::expectDoubleEq(reader->info().spacing, glm::dvec3(0.25, 0.5, 2.0));
    test::expectValues(*reader, testValues(FileScalar::U16));
}

TEST_F(Hdf5Reader, ConvertsFromTheCommandLineChunkedAcrossSlabs) {
    // 40 slices in chunks 16 deep: slabs and chunk layers do not line up.
    const Dims3 d{21, 13, 40};
    std::vector<double> values(size_t(d[0] * d[1] * d[2]));
    for (size_t i = 0; i < values.size(); ++i) values[i] = double((i * 7919) % 65536);
    hid_t f = create("ct.h5");
    DatasetSpec s;
    s.name = "/ct";
    s.dims = {40, 13, 21};
    s.chunk = {16, 8, 8};
    s.deflate = true;
    addDataset(f, s, values);
    H5Fclose(f);
    const auto r = test::runVdiso("convert " + path("ct.h5") + ":/ct " + path("ct.vdiso") +
                                  " --brick 8 --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const BrickStoreReader store(path("ct.vdiso"));
    const std::string samples = test::encodeSamples(values, FileScalar::U16, false);
    EXPECT_EQ(test::compareStoreWithSamples(
                  store, std::vector<unsigned char>(samples.begin(), samples.end())),
              "");
}

// libhdf5 is a module loaded at the first HDF5 file (io/readers/hdf5_module/hdf5_module.h): without
// it, the command refuses the input naming it and the module, and writes nothing.
TEST_F(Hdf5Errors, MissingModuleIsNamed) {
    hid_t f = create("ct.h5");
    DatasetSpec s;
    s.name = "/ct";
    s.dims = {3, 4, 5};
    addDataset(f, s, std::vector<double>(60, 1.0));
    H5Fclose(f);
    ::setenv("VDISO_MODULE_DIR", "/nonexistent", 1);
    const auto r = test::runVdiso("convert " + path("ct.h5") + ":/ct " + path("ct.vdiso"));
    ::unsetenv("VDISO_MODULE_DIR");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find(path("ct.h5") + ":/ct"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("libvdiso_hdf5_module.so"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(path("ct.vdiso")));
}

TEST_F(Hdf5Errors, PathsThatAreNotA3DDatasetAreNamed) {
    hid_t f = create("bad.h5");
    DatasetSpec two;
    two.name = "/image";
    two.dims = {5, 7};
    addDataset(f, two, std::vector<double>(35, 1.0));
    DatasetSpec four;
    four.name = "/group/timeseries";
    four.dims = {2, 4, 5, 7};
    addDataset(f, four, std::vector<double>(280, 1.0));
    hid_t strType = H5Tcopy(H5T_C_S1);
    H5Tset_size(strType, 8);
    const hsize_t dims[3] = {2, 2, 2};
    hid_t space = H5Screate_simple(3, dims, nullptr);
    hid_t d = H5Dcreate2(f, "/names", strType, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Dclose(d);
    H5Sclose(space);
    H5Tclose(strType);
    H5Fclose(f);
    const std::string file = path("bad.h5");
    expectIoError([&] { openHdf5Volume(file + ":/image"); }, {file + ":/image", "is 2-D", "3-D dataset"});
    expectIoError([&] { openHdf5Volume(file + ":/group/timeseries"); }, {"is 4-D"});
    expectIoError([&] { openHdf5Volume(file + ":/group"); }, {file + ":/group", "not a dataset"});
    expectIoError([&] { openHdf5Volume(file + ":/nothing/here"); }, {"no such dataset"});
    expectIoError([&] { openHdf5Volume(file + ":/names"); }, {"string data"});
    expectIoError([&] { openHdf5Volume(file); }, {file, "no 3-D numeric dataset", "/image"});
    test::writeFile(path("text.h5"), "not HDF5 at all");
    expectIoError([&] { openHdf5Volume(path("text.h5") + ":/x"); }, {path("text.h5"), "not an HDF5 file"});
    expectIoError([&] { openHdf5Volume(path("missing.h5")); }, {path("missing.h5")});
    // Two volumes and no path: name one.
    hid_t g = create("two.h5");
    DatasetSpec a, b;
    b.name = "/other";
    addDataset(g, a, testValues(FileScalar::U16));
    addDataset(g, b, testValues(FileScalar::U16));
    H5Fclose(g);
    expectIoError([&] { openHdf5Volume(path("two.h5")); }, {"several 3-D datasets", "/other", "/volume"});
}

// fuzz_hdf5's finding, literally (hex): a superblock that makes libhdf5 1.10.8 allocate and fill
// 4 GB in H5F__super_read. libhdf5 now runs in a helper process whose memory is bounded while it
// opens a file: the file is refused by name, and this process does not grow.
const char* const kHugeSuperblock =
    "894844460d0a1a0a000000000008080004001000000000270000000000000000ffff008048440000000000000000"
    "00004600000000000000000008080004001000000000270000000000000000ffff00804844000000000000000000"
    "0046000000";

TEST_F(Hdf5Errors, HugeSuperblockIsRefusedWithoutTheMemory) {
    std::string bytes;
    for (size_t i = 0; kHugeSuperblock[i] && kHugeSuperblock[i + 1]; i += 2)
        bytes += char(std::stoi(std::string(kHugeSuperblock + i, 2), nullptr, 16));
    const std::string p = write("huge.h5", bytes);
    const auto r = test::runVdiso("convert " + p + " " + path("huge.vdiso"));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find(p + ": "), std::string::npos) << r.output;
    expectIoError([&] { openHdf5Dataset(p, ""); }, {p});
}

// Every truncation of a small chunked file is refused by name.
TEST_F(Hdf5Errors, EveryTruncation) {
    hid_t f = create("t.h5");
    DatasetSpec s;
    s.chunk = {2, 5, 7};
    s.deflate = true;
    addDataset(f, s, test::incompressibleU16Values());
    H5Fclose(f);
    const std::vector<unsigned char> bytes = test::readFile(path("t.h5"));
    for (size_t n = 0; n < bytes.size(); n += 29) {  // a helper process per open: every 29th
        SCOPED_TRACE(n);
        test::writeFile(path("cut.h5"), bytes.data(), n);
        try {
            auto reader = openHdf5Volume(path("cut.h5") + ":/volume");
            test::readAllValues(*reader);
            ADD_FAILURE() << "a truncated file was read";
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(path("cut.h5")), std::string::npos) << e.what();
        }
    }
}

TEST_F(Hdf5Reader, SkipInTheHelperMatchesReading) {
    hid_t f = create("v.h5");
    DatasetSpec contiguous;
    addDataset(f, contiguous, testValues(contiguous.type));
    DatasetSpec chunked = contiguous;
    chunked.name = "/chunked";
    chunked.type = FileScalar::F64;  // converted a slice at a time
    chunked.chunk = {3, 2, 4};
    addDataset(f, chunked, testValues(chunked.type));
    H5Fclose(f);
    for (const char* dataset : {":/volume", ":/chunked"}) {
        SCOPED_TRACE(dataset);
        test::expectSkipMatchesRead([&] { return openHdf5Volume(path("v.h5") + dataset); });
    }
}

}  // namespace
}  // namespace vdiso
