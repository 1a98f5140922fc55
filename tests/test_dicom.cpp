// DICOM series: written here with GDCM (uncompressed and JPEG lossless, several series in one
// folder, a DICOMDIR) and read back sample for sample; the order from ImagePositionPatient, the
// spacing and origin, the rescaling and the store type; and the inputs refused by name: mixed
// series without --series, a missing slice, slices of different sizes, a transfer syntax GDCM
// cannot decode.
#include <gtest/gtest.h>

#include <gdcmAttribute.h>
#include <gdcmDICOMDIRGenerator.h>
#include <gdcmImage.h>
#include <gdcmImageChangeTransferSyntax.h>
#include <gdcmImageWriter.h>
#include <gdcmReader.h>
#include <gdcmTrace.h>
#include <gdcmUIDGenerator.h>
#include <gdcmWriter.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "io/store/brick_store.h"
#include "io/readers/dicom_reader.h"
#include "io/readers/dicom_series.h"
#include "io/error.h"
#include "io/readers/volume_open.h"
#include "tests/reader_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::expectIoError;

// One slice as a scanner writes it.
struct SliceSpec {
    std::string seriesUid = "1.2.826.0.1.3680043.2.1125.1.1";
    std::string description = "HEAD 2.5mm";
    std::string modality = "CT";
    uint32_t columns = 7, rows = 5;
    bool isSigned = false;  // u16 (12 bits stored) or i16
    glm::dvec3 position{-10.0, 20.0, 30.0};
    double orientation[6] = {1, 0, 0, 0, 1, 0};
    double rowSpacing = 0.75, columnSpacing = 0.5;
    double slope = 1.0, intercept = -1024.0;
    int instance = 1;
    bool jpegLossless = false;
    uint32_t pixelDataBytes = 0;  // the pixel data's length: 0 for the whole image
};

// Stored value of pixel i of slice z: within 12 bits, different on every slice.
uint16_t storedValue(int64_t z, int64_t i) { return uint16_t((z * 577 + i * 31) % 4096); }

void writeSlice(const std::string& path, const SliceSpec& s, int64_t z) {
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    gdcm::ImageWriter writer;
    gdcm::Image& image = writer.GetImage();
    image.SetNumberOfDimensions(2);
    image.SetDimension(0, s.columns);
    image.SetDimension(1, s.rows);
    gdcm::PixelFormat format(s.isSigned ? gdcm::PixelFormat::INT16 : gdcm::PixelFormat::UINT16);
    if (!s.isSigned) format.SetBitsStored(12), format.SetHighBit(11);
    image.SetPixelFormat(format);
    image.SetPhotometricInterpretation(gdcm::PhotometricInterpretation::MONOCHROME2);
    image.SetTransferSyntax(gdcm::TransferSyntax::ExplicitVRLittleEndian);
    image.SetSpacing(0, s.columnSpacing);
    image.SetSpacing(1, s.rowSpacing);
    image.SetSpacing(2, 1.0);
    // One axis at a time: SetOrigin(const double*) copies only as many as the image has
    // dimensions, and a slice has two.
    for (unsigned a = 0; a < 3; ++a) image.SetOrigin(a, s.position[int(a)]);
    image.SetDirectionCosines(s.orientation);
    image.SetSlope(s.slope);
    image.SetIntercept(s.intercept);
    std::vector<uint16_t> pixels(size_t(s.columns) * s.rows);
    for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = storedValue(z, int64_t(i));
    gdcm::DataElement data(gdcm::Tag(0x7fe0, 0x0010));
    data.SetByteValue(reinterpret_cast<const char*>(pixels.data()),
                      s.pixelDataBytes ? s.pixelDataBytes : uint32_t(pixels.size() * 2));
    image.SetDataElement(data);
    if (s.jpegLossless) {
        gdcm::ImageChangeTransferSyntax change;
        change.SetTransferSyntax(gdcm::TransferSyntax::JPEGLosslessProcess14_1);
        change.SetInput(image);
        ASSERT_TRUE(change.Change());
        writer.SetImage(change.GetOutput());
    }
    gdcm::DataSet& ds = writer.GetFile().GetDataSet();
    auto put = [&](uint16_t group, uint16_t element, const std::string& value) {
        gdcm::DataElement e(gdcm::Tag(group, element));
        std::string v = value;
        // Values have even lengths: UIDs (SOP class and instance, study, series) pad with NUL,
        // text with a space.
        const bool uid = (group == 0x0008 && (element == 0x0016 || element == 0x0018)) ||
                         (group == 0x0020 && (element == 0x000d || element == 0x000e));
        if (v.size() % 2) v += uid ? '\0' : ' ';
        e.SetByteValue(v.data(), uint32_t(v.size()));
        ds.Replace(e);
    };
    put(0x0008, 0x0016, "1.2.840.10008.5.1.4.1.1.2");  // CT Image Storage
    put(0x0008, 0x0060, s.modality);
    put(0x0008, 0x103e, s.description);
    put(0x0020, 0x000d, "1.2.826.0.1.3680043.2.1125.1");
    put(0x0020, 0x000e, s.seriesUid);
    put(0x0020, 0x0013, std::to_string(s.instance));
    put(0x0010, 0x0020, "VDISO01");  // PatientID and the study's date, ID and time, which a
    put(0x0008, 0x0020, "20260101");  // DICOMDIR's records need
    put(0x0008, 0x0030, "120000");
    put(0x0020, 0x0010, "1");
    put(0x0020, 0x0011, "2");
    gdcm::UIDGenerator uids;
    put(0x0008, 0x0018, uids.Generate());
    writer.SetFileName(path.c_str());
    ASSERT_TRUE(writer.Write()) << path;
}

// A series of `slices` slices along z, 2.5 mm apart from s.position, written to folder/IM<n>
// in an order unrelated to their positions (names reversed, instance numbers scrambled).
std::vector<std::string> writeSeries(const std::string& folder, SliceSpec s, int slices) {
    std::vector<std::string> paths;
    const glm::dvec3 start = s.position;
    for (int z = 0; z < slices; ++z) {
        s.position = start + glm::dvec3(0, 0, 2.5 * z);
        s.instance = (z * 7) % slices + 1;
        const std::string p = folder + "/IM" + std::to_string(slices - z);
        writeSlice(p, s, z);
        paths.push_back(p);
    }
    return paths;
}

std::vector<double> expectedValues(const SliceSpec& s, int slices) {
    std::vector<double> v;
    for (int z = 0; z < slices; ++z)
        for (int64_t i = 0; i < int64_t(s.columns) * s.rows; ++i)
            v.push_back(storedValue(z, i) * s.slope + s.intercept);
    return v;
}

InputOptions seriesOption(const std::string& uid) {
    InputOptions o;
    o.series = uid;
    return o;
}

class DicomTest : public test::ReaderFileTest {
protected:
    void SetUp() override { gdcm::Trace::SetWarning(false); }
};
using DicomReader = DicomTest;
using DicomErrors = DicomTest;

TEST_F(DicomReader, UncompressedAndJpegLosslessSeriesRoundTrip) {
    for (bool jpeg : {false, true}) {
        SCOPED_TRACE(jpeg ? "JPEG lossless" : "uncompressed");
        SliceSpec s;
        s.jpegLossless = jpeg;
        const std::string folder = path(jpeg ? "jpeg" : "plain");
        writeSeries(folder, s, 6);
        test::writeFile(folder + "/notes.txt", "not DICOM");  // passed over
        if (jpeg) {
            gdcm::Reader check;
            check.SetFileName((folder + "/IM1").c_str());
            ASSERT_TRUE(check.Read());
            EXPECT_EQ(check.GetFile().GetHeader().GetDataSetTransferSyntax(),
                      gdcm::TransferSyntax::JPEGLosslessProcess14_1);
        }
        EXPECT_EQ(detectInputFormat(folder, {}), InputFormat::Dicom);
        auto reader = openVolume(folder, {});
        const VolumeInfo& info = reader->info();
        EXPECT_EQ(info.dims, (Dims3{7, 5, 6}));
        EXPECT_EQ(info.type, ScalarType::I16);  // 12-bit stored, intercept -1024
        test::expectDoubleEq(info.spacing, glm::dvec3(0.5, 0.75, 2.5));
        test::expectDoubleEq(info.origin, glm::dvec3(-10.0, 20.0, 30.0));
        EXPECT_EQ(reader->files().size(), 6u);
        test::expectValues(*reader, expectedValues(s, 6));
    }
}

TEST_F(DicomReader, OrderFollowsTheSliceNormal) {
    // Sagittal slices: rows along y, columns along -z, so the normal is -x and the slice
    // nearest +x... comes last: positions decrease in x as z (the slice index) grows.
    SliceSpec s;
    s.isSigned = true;
    s.intercept = 0.0;
    const double sagittal[6] = {0, 1, 0, 0, 0, -1};
    std::memcpy(s.orientation, sagittal, sizeof(sagittal));
    for (int z = 0; z < 4; ++z) {
        s.position = glm::dvec3(50.0 - 1.5 * z, 0.0, 0.0);
        s.instance = 4 - z;  // InstanceNumber says the opposite order: positions win
        writeSlice(path("sag/s" + std::to_string(z)), s, z);
    }
    auto reader = openDicomVolume(path("sag"), "");
    EXPECT_EQ(reader->info().type, ScalarType::I16);
    EXPECT_DOUBLE_EQ(reader->info().spacing.z, 1.5);
    test::expectDoubleEq(reader->info().origin, glm::dvec3(50.0, 0.0, 0.0));
    std::vector<double> want;
    for (int z = 0; z < 4; ++z)
        for (int64_t i = 0; i < 35; ++i) want.push_back(storedValue(z, i));
    test::expectValues(*reader, want);
}

// An oblique series (rows along (1,1,0)/sqrt 2, columns along -z: the normal is (-1,1,0)/sqrt 2),
// written with its files in the opposite order to its positions: the orientation is the row
// cosines, the column cosines and the normal (PS3.3 C.7.6.2.1.1); the origin is the position of
// the first slice along the normal. DICOM's patient coordinates are LPS already.
TEST_F(DicomReader, ObliqueOrientationIsKept) {
    SliceSpec s;
    const double r = std::sqrt(0.5);
    const double oblique[6] = {r, r, 0, 0, 0, -1};
    std::memcpy(s.orientation, oblique, sizeof(oblique));
    const glm::dvec3 normal(-r, r, 0.0), start(12.0, -40.0, 7.5);
    for (int z = 0; z < 4; ++z) {
        s.position = start + normal * (2.0 * (3 - z));
        s.instance = z + 1;
        writeSlice(path("oblique/s" + std::to_string(z)), s, 3 - z);
    }
    auto reader = openDicomVolume(path("oblique"), "");
    const VolumeInfo& info = reader->info();
    EXPECT_TRUE(info.hasOrientation);
    test::expectDirection(info.direction, glm::dmat3(glm::dvec3(r, r, 0), glm::dvec3(0, 0, -1), normal), 1e-5);
    test::expectDoubleEq(info.origin, start);
    EXPECT_NEAR(info.spacing.z, 2.0, 1e-5);
    test::expectValues(*reader, expectedValues(s, 4));
}

TEST_F(DicomReader, FractionalRescaleIsStoredAsFloat) {
    SliceSpec s;
    s.slope = 0.5;
    s.intercept = 3.25;
    writeSeries(path("pet"), s, 3);
    auto reader = openDicomVolume(path("pet"), "");
    EXPECT_EQ(reader->info().type, ScalarType::F32);
    test::expectValues(*reader, expectedValues(s, 3));
}

TEST_F(DicomReader, SeriesChosenFromAMixedFolderOneFileAndAList) {
    SliceSpec a, b;
    b.seriesUid = "1.2.826.0.1.3680043.2.1125.1.2";
    b.description = "SCOUT";
    b.columns = 9;
    b.rows = 4;
    writeSeries(path("study/a"), a, 5);
    const std::vector<std::string> bFiles = writeSeries(path("study/b"), b, 3);
    auto chosen = openVolume(path("study"), seriesOption(b.seriesUid));
    EXPECT_EQ(chosen->info().dims, (Dims3{9, 4, 3}));
    test::expectValues(*chosen, expectedValues(b, 3));
    // One file: the series it is part of, from its folder.
    auto fromFile = openVolume(bFiles[1], {});
    EXPECT_EQ(fromFile->info().dims, (Dims3{9, 4, 3}));
    // A list of files, as a shell glob gives them.
    auto fromList = openVolume(bFiles, {});
    test::expectValues(*fromList, expectedValues(b, 3));
}

TEST_F(DicomReader, Dicomdir) {
    SliceSpec s;
    const std::vector<std::string> files = writeSeries(path("cd/S1"), s, 4);
    gdcm::DICOMDIRGenerator generator;
    std::vector<std::string> names;
    for (const std::string& f : files) names.push_back(f);
    generator.SetFilenames(names);
    generator.SetRootDirectory(path("cd"));
    generator.SetDescriptor("VDISO");
    ASSERT_TRUE(generator.Generate());
    gdcm::Writer writer;
    writer.SetFile(generator.GetFile());
    writer.SetFileName(path("cd/DICOMDIR").c_str());
    ASSERT_TRUE(writer.Write());
    EXPECT_EQ(detectInputFormat(path("cd/DICOMDIR"), {}), InputFormat::Dicom);
    auto reader = openVolume(path("cd/DICOMDIR"), {});
    EXPECT_EQ(reader->info().dims, (Dims3{7, 5, 4}));
    test::expectValues(*reader, expectedValues(s, 4));
}

TEST_F(DicomReader, ConvertsFromTheCommandLine) {
    SliceSpec s;
    s.columns = 20;
    s.rows = 18;
    s.jpegLossless = true;
    writeSeries(path("ct"), s, 17);
    const auto r = test::runVdiso("convert " + path("ct") + " " + path("ct.vdiso") +
                                  " --brick 8 --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const BrickStoreReader store(path("ct.vdiso"));
    std::vector<int16_t> samples;
    for (double v : expectedValues(s, 17)) samples.push_back(int16_t(v));
    const auto* bytes = reinterpret_cast<const unsigned char*>(samples.data());
    EXPECT_EQ(test::compareStoreWithSamples(
                  store, std::vector<unsigned char>(bytes, bytes + samples.size() * 2)),
              "");
}

// GDCM is a module loaded at the first DICOM file (io/readers/gdcm_module/gdcm_module.h): without it,
// the command refuses the input naming it and the module, and writes nothing.
TEST_F(DicomErrors, MissingModuleIsNamed) {
    SliceSpec s;
    writeSeries(path("ct"), s, 3);
    ::setenv("VDISO_MODULE_DIR", "/nonexistent", 1);
    const auto r = test::runVdiso("convert " + path("ct") + " " + path("ct.vdiso"));
    ::unsetenv("VDISO_MODULE_DIR");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find(path("ct")), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("libvdiso_gdcm_module.so"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(path("ct.vdiso")));
}

TEST_F(DicomErrors, MixedSeriesWithoutSeriesOption) {
    SliceSpec a, b;
    b.seriesUid = "1.2.826.0.1.3680043.2.1125.1.2";
    b.description = "SCOUT";
    b.modality = "MR";
    b.columns = 9;
    b.rows = 4;
    writeSeries(path("study/a"), a, 5);
    writeSeries(path("study/b"), b, 3);
    expectIoError([&] { openVolume(path("study"), {}); },
                  {path("study"), "holds 2 series", "choose one by its SeriesInstanceUID", a.seriesUid,
                   "\"HEAD 2.5mm\"  CT  5 slices  7 x 5", b.seriesUid, "\"SCOUT\"  MR  3 slices  9 x 4"});
    expectIoError([&] { openVolume(path("study"), seriesOption("1.2.3")); },
                  {"holds no series 1.2.3", a.seriesUid});
    const auto r = test::runVdiso("convert " + path("study") + " " + path("out.vdiso"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("--series"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(path("out.vdiso")));
}

TEST_F(DicomErrors, MissingSliceIsNamed) {
    SliceSpec s;
    const std::vector<std::string> files = writeSeries(path("gap"), s, 6);
    std::filesystem::remove(files[3]);  // z = 3, at 37.5
    expectIoError([&] { openVolume(path("gap"), {}); },
                  {path("gap"), "a gap of 5 mm", files[2], files[4], "2.5 mm apart",
                   "a slice is missing"});
}

TEST_F(DicomErrors, UnevenAndDuplicatePositions) {
    SliceSpec s;
    for (int z = 0; z < 4; ++z) {
        s.position = glm::dvec3(0, 0, z < 3 ? 2.0 * z : 2.0 * z + 0.5);
        writeSlice(path("uneven/s" + std::to_string(z)), s, z);
    }
    expectIoError([&] { openVolume(path("uneven"), {}); }, {"a gap of 2.5 mm", "unevenly spaced"});
    s.position = glm::dvec3(0, 0, 2.0);
    writeSlice(path("dup/a"), s, 0);
    writeSlice(path("dup/b"), s, 1);
    s.position = glm::dvec3(0, 0, 4.0);
    writeSlice(path("dup/c"), s, 2);
    expectIoError([&] { openVolume(path("dup"), {}); }, {"same position"});
}

TEST_F(DicomErrors, SlicesOfDifferentSizes) {
    SliceSpec s;
    writeSeries(path("sizes"), s, 3);
    s.columns = 8;
    s.position = glm::dvec3(-10.0, 20.0, 37.5);
    writeSlice(path("sizes/IM9"), s, 3);
    expectIoError([&] { openVolume(path("sizes"), {}); },
                  {path("sizes"), "8 x 5 uint16", "unlike the 7 x 5 uint16",
                   "same size and type"});
}

TEST_F(DicomErrors, TransferSyntaxGdcmCannotDecode) {
    SliceSpec s;
    s.jpegLossless = true;
    const std::vector<std::string> files = writeSeries(path("jpip"), s, 3);
    // Relabel one file's JPEG lossless pixel data as JPIP Referenced (the pixels live on a
    // server): a UID of the same length, patched in the file meta header.
    std::vector<unsigned char> bytes = test::readFile(files[1]);
    const std::string from = "1.2.840.10008.1.2.4.70", to = "1.2.840.10008.1.2.4.94";
    auto at = std::search(bytes.begin(), bytes.end(), from.begin(), from.end());
    ASSERT_NE(at, bytes.end());
    std::copy(to.begin(), to.end(), at);
    test::writeFile(files[1], bytes.data(), bytes.size());
    expectIoError(
        [&] {
            auto reader = openVolume(path("jpip"), {});
            test::readAllValues(*reader);
        },
        {files[1], "1.2.840.10008.1.2.4.94"});
}

// Pixel data shorter than Rows x Columns x BitsAllocated/8 says: GDCM would copy the rest from
// beyond its buffer in the helper (a process's memory in the user's volume). Refused, naming the
// file and both lengths, before GDCM decodes it.
TEST_F(DicomErrors, PixelDataShorterThanItsHeaderIsRefused) {
    SliceSpec s;
    s.rows = 1028;
    s.columns = 6;
    s.isSigned = true;
    s.pixelDataBytes = 48;
    const std::vector<std::string> files = writeSeries(path("short"), s, 3);
    for (const std::string& f : files) ASSERT_LT(std::filesystem::file_size(f), 2000u);
    expectIoError(
        [&] {
            auto reader = openVolume(path("short"), {});
            test::readAllValues(*reader);
        },
        {path("short/IM"), "pixel data holds 48 bytes", "1028 x 6 x 2", "needs 12336"});
    // One byte short of the image is refused too; the whole image reads.
    s.pixelDataBytes = 12336 - 2;
    writeSeries(path("short2"), s, 2);
    expectIoError(
        [&] {
            auto reader = openVolume(path("short2"), {});
            test::readAllValues(*reader);
        },
        {path("short2/IM"), "holds 12334 bytes", "needs 12336"});
    s.pixelDataBytes = 0;
    writeSeries(path("whole"), s, 2);
    auto reader = openVolume(path("whole"), {});
    test::readAllValues(*reader);
}

// Encapsulated pixel data holding only its basic offset table, and a table that is not a whole
// number of offsets: refused by name before GDCM sees them (its BasicOffsetTable asserts).
TEST_F(DicomErrors, EncapsulatedPixelDataWithoutFragmentsIsRefused) {
    SliceSpec s;
    s.jpegLossless = true;
    const std::vector<std::string> files = writeSeries(path("jpeg"), s, 2);
    const std::vector<unsigned char> bytes = test::readFile(files[0]);
    // The pixel data element: (7FE0,0010) OB, reserved, undefined length; then the offset table.
    const unsigned char tag[] = {0xe0, 0x7f, 0x10, 0x00, 'O', 'B', 0, 0, 0xff, 0xff, 0xff, 0xff};
    const auto at = std::search(bytes.begin(), bytes.end(), std::begin(tag), std::end(tag));
    ASSERT_NE(at, bytes.end());
    const size_t table = size_t(at - bytes.begin()) + sizeof(tag);
    // Only the (empty) offset table, then the sequence end.
    std::vector<unsigned char> noFragment(bytes.begin(), bytes.begin() + std::ptrdiff_t(table));
    const unsigned char emptyTableAndEnd[] = {0xfe, 0xff, 0x00, 0xe0, 0, 0, 0, 0,
                                              0xfe, 0xff, 0xdd, 0xe0, 0, 0, 0, 0};
    noFragment.insert(noFragment.end(), std::begin(emptyTableAndEnd), std::end(emptyTableAndEnd));
    test::writeFile(files[0], noFragment.data(), noFragment.size());
    expectIoError(
        [&] {
            auto reader = openDicomFiles(files, "");
            test::readAllValues(*reader);
        },
        {files[0], "no fragment"});
    // An offset table of 6 bytes.
    std::vector<unsigned char> oddTable(bytes.begin(), bytes.begin() + std::ptrdiff_t(table));
    const unsigned char table6[] = {0xfe, 0xff, 0x00, 0xe0, 6, 0, 0, 0, 0, 0, 0, 0, 0, 0,
                                    0xfe, 0xff, 0xdd, 0xe0, 0, 0, 0, 0};
    oddTable.insert(oddTable.end(), std::begin(table6), std::end(table6));
    test::writeFile(files[0], oddTable.data(), oddTable.size());
    expectIoError(
        [&] {
            auto reader = openDicomFiles(files, "");
            test::readAllValues(*reader);
        },
        {files[0], "basic offset table of 6 bytes"});
    // fuzz_dicom's finding: an offset table claiming 3.7 GB in a small file, which GDCM reads
    // (and allocated) with the header, before the pixels were asked for.
    std::vector<unsigned char> hugeTable = bytes;
    const unsigned char claim[] = {0x00, 0x00, 0x00, 0xe0};
    std::copy(std::begin(claim), std::end(claim), hugeTable.begin() + std::ptrdiff_t(table + 4));
    test::writeFile(files[0], hugeTable.data(), hugeTable.size());
    expectIoError([&] { openDicomFiles(files, ""); }, {files[0], "3758096384 bytes, past the end"});
}

TEST_F(DicomErrors, EveryTruncationOfASlice) {
    SliceSpec s;
    const std::vector<std::string> files = writeSeries(path("t"), s, 2);
    const std::vector<unsigned char> bytes = test::readFile(files[0]);
    for (size_t n = 0; n < bytes.size(); n += 3) {
        SCOPED_TRACE(n);
        test::writeFile(files[0], bytes.data(), n);
        try {
            auto reader = openDicomFiles(files, "");
            test::readAllValues(*reader);
            ADD_FAILURE() << "a truncated slice was read";
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(path("t")), std::string::npos) << e.what();
        }
    }
}

// fuzz_dicom's findings, literally (hex): GDCM's assertions abort the process on them, in
// gdcm::ReadExplicitDataElement on a meta header element with an unknown VR, in
// gdcm::JPEG16Codec::GetHeaderInfo on a JPEG stream that makes libjpeg warn, and in
// gdcm::BasicOffsetTable::Read while reading the header. The first is now refused by the
// structure check, the others by GDCM's helper process dying, each by name, and the test
// process goes on. A fourth made GDCM allocate 3.4 GB for a fragment its header claims: the
// helper's memory is bounded, and the file is refused or read without it.
const char* const kMetaHeaderUnknownVR =
    "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "0000000000000000000000000000000000000000000000000000000000000000000000004449434d02000000554c"
    "0400ba000000020001004f4200000200000000010200020055491a00312e322e3834302e31303030382e352e312e"
    "342e312e312e32000200030055490a00312e322e332e342e35200200100055491600312e322e3834302e31303030"
    "382e312e322e342e37300200120055493200312e322e3832362e302e312e333638303034332e322e313134332e31"
    "30372e3130342e3130332e3131352e332e302e323100020013005a480c004744434d20332e302e32312002001600"
    "414504004744434d08001600554e00001a000000312e322e3834302e31303030382e352e312e342e312e312e3200"
    "08001800554e00000a000000312e322e332e342e35200800200044410800323032363131323308003000544d0e00"
    "3231333630352e38393833333020080050005348000008006000554e000002000000435408009000504e00001000"
    "1000504e0000100020004c4f00001000300044410000100040004353000020000d0055494000312e322e3832362e"
    "302e312e333638303034332e322e313134332e363734343637343235373431313437383732383233353432383738"
    "3638333430313738313720000e00554e000008000000312e322e332e342020001000534800002000110049530000"
    "20001300554e00000200000031202000320044530a002d31305c32305c3330202000370044530c00315c305c305c"
    "305c315c3020280002005553020001002800040043530c004d4f4e4f4348524f4d45322028001000555302000400"
    "2800110055530200060028003000445306002e37355c2e352800000155530200100028000101555302000c002800"
    "0201555302000b002800030155530200000028005210445306002d31303234202800531044530200312028005410"
    "4c4f02005553e07f10004f420000fffffffffeff00e000000000feff00e050000000ffd8ffc3000b100004000601"
    "011100ffc400160001010100000000000c00000000000000080a10ffda0008010100010000c964b2592c96b844b2"
    "592c964b5c22592c964b25ae112c964b2592dfffd900feffdde000000000";
const char* const kJpegHeaderWarning =
    "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "0000000000000000000000000000000080000000000000000000000000000000000000004449434d02000000554c"
    "0400ba000000020001004f4200000200000000010200544455491a00312e322e3834302e31303030382e352e312e"
    "342e312e312e32000200038055490a00312e322e332e342e35200200100055491600312e322e3834302e31303030"
    "382e312e322e342e37300200120055493200312e322e3832362e302e312e333638303034332e322e313134332e31"
    "30372e3130342e3135332e3131352e332e302e3231000200130053480c004744434d20332e302e32312002001600"
    "414504004744434d08001600554e00001a000000312e322e3834302e31303030382e352e312e342e312e312e3200"
    "08001800554e00000a000000312e322e332e342e35200800200044410800323032363131323308003000544d0e00"
    "3231333630352e38393833333020080050005348000008006000554e000002000000435408009000504e00001000"
    "1000504e0000100020004c4f00001000300044410000100040004353000020000d0055494000312e322e3832362e"
    "302e312e333638303034332e322e313134332e363734343637343030303030303030303030393135383337363733"
    "3439373931343735333220000e00554e000008000000312e322e332e342020001000534800002000110049530000"
    "20001300554e00000200000031202000320044530a002d31305c32305c3330202000370044530c00315c305c305c"
    "305c315c3020280002005553020001000028040043530c004d4f4e4f4348524f4d45322028001000555302000400"
    "2800110055530200060028003000445306002e37355c2c352800000155530200100028000101555302000c002800"
    "0201555302000b002800030155530200000028005210445306002d31303234202800531044530200312028005410"
    "4c4f02005553e07f10004f420000fffffffffeff00e000000000feff00e050000000ffd8ffc3000b100004000601"
    "0111007fc400160001010100000000000000000000000000080a10ffda0008010100010000c964b2592c96b844b2"
    "592c964b5c22592c964b25ae112c964b2592dfffd900feffdde000000000";

const char* const kHeaderOffsetTable =
    "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "0000000000000000000000000000000027000000000000000000000000000000000000004449434d02000000554c"
    "0400ba000000020001004f4200000200000000010200020055491a00312e322e3834302e31303030382e352e312e"
    "342e312e312e32000200030055490a00312e322e332e342e35200200100055491600312e322e3834302e31303030"
    "382e312e322e342e37300200120055493200312e322e3832362e302e312e333638303034332e322e313134332e31"
    "30372e3130342e3130332e3131352e332e302e3231000200130053480c004744434d20332e302e32312002001600"
    "414504004744434d08001600554e00001a000000312e322e3834302e31303030382e352e312e342e312e312e3200"
    "08001800554e00000a000000312e322e332e342e35200800200044410800323032363131323308003000544d0e00"
    "3231333630352e38393833333020080050005348000008006000554e000002000000435408009000504e00001000"
    "1000504e0000100020004c4f00001000300044410000100040004353000020000d0055494000312e322e3832362e"
    "302e312e333638303034332e322e313134332e363734343637343235373431313437383732383233353432383738"
    "3638333430313738313720000e00554e000008000000312e322e332e342020001000534800002000110049530000"
    "20001300554e00000200000031202000320044530a002d31305c32305c3330202000370044530c00315c305c305c"
    "305c315c3020280002005553020001002800040043530c004d4f4e4f4348524f4d45322028001000555302000400"
    "2800110055530200060028003000445306002e37355c2e3528000001555302001000280001015553020000002800"
    "0201555302000b002800030155530200000028005210445306002d31303234202800531044530200312028005410"
    "4c4f02005553e07f10004f420000fffffffffeff00e000002300feff00e050000000ffd8ffc3000b100004000601"
    "011100ffc400160001010100000000000000000000000000080a10ffda0008010100010000c964b2592c96b844b2"
    "592c964b5c22592c964b25ae112c964b2592dfffd900feffdd2e312e3300";

const char* const kHugeFragment =
    "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "0000000000000000000000000000000000000000000000000000000000000000000000004449434d02000000554c"
    "0400ba000000020001004f4200000200000000010200020055491a00312e322e3834302e31303030382e352e312e"
    "342e312e312e32000200030055490a00312e322e332e342e35200200100055491600312e322e3834302e31303030"
    "382e312e322e342e37300200120055493200312e322e3832362e302e312e333638303034332e322e313134332e31"
    "30372e3130342e3130332e3131352e332e302e3231000200130053480c004744434d20332e302e32312002001600"
    "414504004744434d08001600554e00001a000000312e322e3834302e31303030382e352e312e342e312e312e3200"
    "08001800554e00000a000000312e322e332e342e35200800200044410800eeffffffffffff7f08003000544d0e00"
    "3231333630352e38393833333020080050005348000008006000554e000002000000435408009000504e00001000"
    "1000504e0000100020004c4f00001000300044410000100040004353000020000d0055494000312e322e3832362e"
    "302e312e333638303034332e322e313134332e363734343637343235373431313437383732383233353432383738"
    "36383334303137383037e8000e00554e000008000000312e322e332e342020001000534800002000110049530000"
    "20001300554e00000200000031202000320044530a002d31305c32305c3330202000370044530c00315c305c305c"
    "305c315c3020280002005553020001002800040043530c004d4f4e4f4348524f4d45322028001000555302000400"
    "2800110055530200060028003028445306002e37355c2e352800000155530200100028000101555302000c002800"
    "0201555302000b002800030155530200000028005210445306002d31303234202800531044530200312028005410"
    "4c4f02005553e07f10004f420000fffffffffeff00e000000000feff00e050000000ffd8ffc3000b100004000601"
    "0111c400ff16000001010100000000000000000000000000080a10ffda0008010100010000c964b2592c96b844b2"
    "592c964b5c22592c964b25ae112c964b2592dfffd900feffdde0000000cb";

// fuzz_dicom (campaign): JPEG lossless pixel data whose frame header claims 250-bit samples;
// GDCM's JPEG codec segfaulted on it in the helper.
constexpr const char* kJpeg250Bits =
    "000000000000000000000000000000000000000000000000000000000000f8ffffff000000000000000000000000"
    "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "0040000000000000000000000000000000000000000000000000000000000000000000004449434d02000000554c"
    "0400ba000000020001004f4200000200000000010200020055491a00312e322e3834302e31303030382e352e312e"
    "342e312e312e32000200030055490a00312e322e332e342e35200200100055491600312e322e3834302e31303030"
    "382e312e322e342e37300200120055493200312e322e3832362e302e312e333638303034332e322e313134332e31"
    "30372e3130342e3130332e3131352e332e302e3231000200130053480c004744434d20332e302e32312002001600"
    "414504004744434d08001600554e00001a000000312e322e3834302e31303030382e352e312e342e312e312e3200"
    "08001800554e00000a000000312e322e332e342e35200800200044410800323032363131323308003000544d0e00"
    "3231333630352e38393833333020080050005348000008006000554e000002000000435408009000504e00001000"
    "1000504e0000100020004c4f00001000300044410000100040004353000020000d0055494000312e322e3832362e"
    "302e312e333638303034332e322e313134332e363734343637343235373431313437383732383233353432383738"
    "3638333430313738313720000e00554e000008000000312e322e332e342020001000534800002000110049530000"
    "20001300554e00000200000031202000320044530a002d31305c32305c3330202000370044530c00315e305c305c"
    "305c315c3020280002005553020001002800040043530c004d4f4e4f4348524f4d45322028001000555302000400"
    "2800110055530200060028003000445306002e37355c2e35280000015553020010002800010a555302000c002800"
    "0201555302000b002800030155530200000028005210445306002d31303234202800531044530200312028005410"
    "4c4f02005553e07f10004f420000fffffffffeff00e000000000feff00e050000000ffd8ffc3000bfaff60ff0601"
    "011100ffc400160001010100000000000000000000000000080a10ffda0008010100010000c964b2592c96b844b2"
    "592c964b5c22592c964b25ae112c964b2592dfffd900feffdde000000000";

std::string fromHex(const char* hex) {
    std::string bytes;
    for (size_t i = 0; hex[i] && hex[i + 1]; i += 2)
        bytes += char(std::stoi(std::string(hex + i, 2), nullptr, 16));
    return bytes;
}

TEST_F(DicomErrors, FuzzFindingsAreRefusedByName) {
    for (const auto& [name, hex] : {std::pair{"meta.dcm", kMetaHeaderUnknownVR},
                                    std::pair{"jpeg.dcm", kJpegHeaderWarning},
                                    std::pair{"table.dcm", kHeaderOffsetTable}}) {
        SCOPED_TRACE(name);
        const std::string p = write(name, fromHex(hex));
        expectIoError(
            [&] {
                auto reader = openDicomImage(p);
                test::readAllValues(*reader);
            },
            {p});
    }
    const std::string jpeg250 = write("jpeg250.dcm", fromHex(kJpeg250Bits));
    expectIoError(
        [&] {
            auto reader = openDicomImage(jpeg250);
            test::readAllValues(*reader);
        },
        {jpeg250, "JPEG data describes a 65286 x 65376 image of 250-bit samples", "6 x 4"});
    const std::string huge = write("huge.dcm", fromHex(kHugeFragment));
    try {
        auto reader = openDicomImage(huge);
        test::readAllValues(*reader);
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(huge), std::string::npos) << e.what();
    }
    // And a sound series still reads after them.
    SliceSpec s;
    s.jpegLossless = true;
    writeSeries(path("after"), s, 2);
    auto reader = openDicomVolume(path("after"), "");
    test::expectValues(*reader, expectedValues(s, 2));
}

// The geometry rules on headers alone.
TEST(DicomSeries, InstanceNumberOrdersSlicesWithoutPositions) {
    std::vector<DicomHeader> headers(3);
    for (int i = 0; i < 3; ++i) {
        headers[size_t(i)].path = "f" + std::to_string(i);
        headers[size_t(i)].rows = 4;
        headers[size_t(i)].columns = 4;
        headers[size_t(i)].instanceNumber = 3 - i;
        headers[size_t(i)].sliceSpacing = 1.25;
        headers[size_t(i)].bitsStored = 12;
    }
    const DicomVolume v = arrangeDicomSeries(headers, "x");
    EXPECT_EQ(v.slices.front().path, "f2");
    EXPECT_EQ(v.info.spacing.z, 1.25);
    EXPECT_EQ(v.info.type, ScalarType::U16);
    headers[0].slope = 2.0;  // integral, but 4095 * 2 still fits i16
    EXPECT_EQ(arrangeDicomSeries(headers, "x").info.type, ScalarType::I16);
    headers[0].bitsStored = 16;  // 65535 * 2 does not
    EXPECT_EQ(arrangeDicomSeries(headers, "x").info.type, ScalarType::F32);
    headers[1].instanceNumber = 1;
    expectIoError([&] { arrangeDicomSeries(headers, "x"); }, {"same InstanceNumber"});
}

// Slices ordered by InstanceNumber have no orientation; ordered by position, they have one,
// with k along the normal they were sorted by (here a flipped axial stack: columns along -y).
TEST(DicomSeries, OrientationOnlyFromPositions) {
    std::vector<DicomHeader> headers(3);
    for (int i = 0; i < 3; ++i) {
        DicomHeader& h = headers[size_t(i)];
        h.path = "f" + std::to_string(i);
        h.rows = h.columns = 4;
        h.instanceNumber = i + 1;
    }
    EXPECT_FALSE(arrangeDicomSeries(headers, "x").info.hasOrientation);
    for (int i = 0; i < 3; ++i) {
        headers[size_t(i)].position = glm::dvec3(1.0, 2.0, 3.0 - 1.5 * i);
        headers[size_t(i)].orientation = std::array<double, 6>{1, 0, 0, 0, -1, 0};
    }
    const DicomVolume v = arrangeDicomSeries(headers, "x");
    EXPECT_TRUE(v.info.hasOrientation);
    EXPECT_EQ(v.info.direction, glm::dmat3(1, 0, 0, 0, -1, 0, 0, 0, -1));
    EXPECT_EQ(v.info.origin, glm::dvec3(1.0, 2.0, 3.0));
    EXPECT_EQ(v.slices.front().path, "f0");
}

TEST(DicomSeries, ShearedStackIsRefused) {
    std::vector<DicomHeader> headers(3);
    for (int i = 0; i < 3; ++i) {
        DicomHeader& h = headers[size_t(i)];
        h.path = "f" + std::to_string(i);
        h.rows = h.columns = 4;
        h.position = glm::dvec3(0.0, 0.5 * i, 2.0 * i);  // 14 degrees of gantry tilt
        h.orientation = std::array<double, 6>{1, 0, 0, 0, 1, 0};
    }
    expectIoError([&] { arrangeDicomSeries(headers, "x"); }, {"gantry tilt"});
}

TEST_F(DicomReader, SkipPassesOverFilesAndMatchesReading) {
    SliceSpec s;
    writeSeries(path("series"), s, 6);
    test::expectSkipMatchesRead([&] { return openVolume(path("series"), {}); });
}

}  // namespace
}  // namespace vdiso
