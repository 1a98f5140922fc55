// A CT series written with GDCM, a file per slice, as tests/test_dicom.cpp writes its small ones.
#include <gdcmDataElement.h>
#include <gdcmImage.h>
#include <gdcmImageChangeTransferSyntax.h>
#include <gdcmImageWriter.h>
#include <gdcmTrace.h>
#include <gdcmUIDGenerator.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "bench/inputs/writers.h"

namespace vdiso::bench {
namespace {

constexpr double kPixelMm = 0.5, kSliceMm = 0.5;
// 12 bits stored, as CT scanners write: the reader then knows that stored + intercept fits i16
// and stores i16 (with all 16 bits stored, -32768 - 1024 would not fit, and it stores f32).
// The head's samples reach 1910.
constexpr uint16_t kMaxStored = 2047;

// Sets a text or UID element, padded to an even length as DICOM requires (UIDs with NUL).
void put(gdcm::DataSet& ds, uint16_t group, uint16_t element, std::string value, bool uid = false) {
    if (value.size() % 2) value += uid ? '\0' : ' ';
    gdcm::DataElement e(gdcm::Tag(group, element));
    e.SetByteValue(value.data(), uint32_t(value.size()));
    ds.Replace(e);
}

}  // namespace

void writeDicomSeries(const HeadSlices& head, const std::string& folder, int64_t slices,
                      bool jpegLossless) {
    gdcm::Trace::SetWarning(false);
    const int64_t n = head.size(), half = n / 2;
    if (slices < 2 || slices > n)
        throw std::runtime_error(folder + ": " + std::to_string(slices) + " slices of a head of " +
                                 std::to_string(n) + " cannot be written");
    std::filesystem::create_directories(folder);
    const int64_t z0 = (n - slices) / 2;  // the middle slices
    gdcm::UIDGenerator uids;
    const std::string study = uids.Generate(), series = uids.Generate();
    std::vector<uint16_t> full(size_t(n * n));
    std::vector<int16_t> pixels(size_t(half * half));
    for (int64_t k = 0; k < slices; ++k) {
        head.read(z0 + k, 1, full.data());
        for (int64_t y = 0; y < half; ++y)
            for (int64_t x = 0; x < half; ++x)
                pixels[size_t(y * half + x)] =
                    int16_t(std::min<uint16_t>(full[size_t(2 * y * n + 2 * x)], kMaxStored));

        gdcm::ImageWriter writer;
        gdcm::Image& image = writer.GetImage();
        image.SetNumberOfDimensions(2);
        image.SetDimension(0, unsigned(half));
        image.SetDimension(1, unsigned(half));
        gdcm::PixelFormat format(gdcm::PixelFormat::INT16);
        format.SetBitsStored(12);
        format.SetHighBit(11);
        image.SetPixelFormat(format);
        image.SetPhotometricInterpretation(gdcm::PhotometricInterpretation::MONOCHROME2);
        image.SetTransferSyntax(gdcm::TransferSyntax::ExplicitVRLittleEndian);
        image.SetSpacing(0, kPixelMm);
        image.SetSpacing(1, kPixelMm);
        image.SetSpacing(2, kSliceMm);
        // One axis at a time: SetOrigin(const double*) copies only as many values as the image
        // has dimensions, and a slice has two.
        const double origin[3] = {-kPixelMm * double(half) / 2, -kPixelMm * double(half) / 2,
                                  kSliceMm * double(k)};
        for (unsigned a = 0; a < 3; ++a) image.SetOrigin(a, origin[a]);
        const double orientation[6] = {1, 0, 0, 0, 1, 0};
        image.SetDirectionCosines(orientation);
        image.SetSlope(1.0);
        image.SetIntercept(-1024.0);
        gdcm::DataElement data(gdcm::Tag(0x7fe0, 0x0010));
        data.SetByteValue(reinterpret_cast<const char*>(pixels.data()),
                          uint32_t(pixels.size() * sizeof(int16_t)));
        image.SetDataElement(data);
        if (jpegLossless) {
            gdcm::ImageChangeTransferSyntax change;
            change.SetTransferSyntax(gdcm::TransferSyntax::JPEGLosslessProcess14_1);
            change.SetInput(image);
            if (!change.Change())
                throw std::runtime_error(folder + ": GDCM cannot encode JPEG Lossless");
            writer.SetImage(change.GetOutput());
        }
        gdcm::DataSet& ds = writer.GetFile().GetDataSet();
        put(ds, 0x0008, 0x0016, "1.2.840.10008.5.1.4.1.1.2", true);  // CT Image Storage
        put(ds, 0x0008, 0x0018, uids.Generate(), true);
        put(ds, 0x0008, 0x0060, "CT");
        put(ds, 0x0008, 0x103e, "HEAD bench");
        put(ds, 0x0010, 0x0020, "VDISOBENCH");
        put(ds, 0x0018, 0x0050, "0.5");  // SliceThickness
        put(ds, 0x0020, 0x000d, study, true);
        put(ds, 0x0020, 0x000e, series, true);
        put(ds, 0x0020, 0x0013, std::to_string(k + 1));
        char name[32];
        std::snprintf(name, sizeof(name), "IM%05lld.dcm", (long long)(k + 1));
        const std::string path = folder + "/" + name;
        writer.SetFileName(path.c_str());
        if (!writer.Write()) throw std::runtime_error(path + ": GDCM cannot write it");
    }
}

}  // namespace vdiso::bench
