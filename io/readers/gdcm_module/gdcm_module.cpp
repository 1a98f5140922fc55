// The GDCM module (see gdcm_module.h): every call vdiso makes into GDCM, in the helper process
// io/readers/gdcm_process.h forks. Requests and replies are as io/readers/gdcm_process.cpp sends and reads them.
#include "io/readers/gdcm_module/gdcm_module.h"

#include <gdcmDataSet.h>
#include <gdcmFile.h>
#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmReader.h>
#include <gdcmSequenceOfItems.h>
#include <gdcmStringFilter.h>
#include <gdcmTrace.h>
#include <gdcmTransferSyntax.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "io/readers/dicom_series.h"
#include "io/readers/dicom_wire.h"
#include "io/readers/helper_wire.h"

namespace vdiso {
namespace {

// What is wrong with a file, without its path (the parent names the file).
struct Refusal : std::runtime_error {
    using std::runtime_error::runtime_error;
};

[[noreturn]] void refuse(const std::string& message) {
    throw Refusal(message);
}

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\0')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.remove_suffix(1);
    return s;
}

// The backslash-separated numbers of a DS or IS value; nullopt if any is not a finite number or
// there are not `count` of them.
std::optional<std::vector<double>> parseNumbers(std::string_view text, size_t count) {
    std::vector<double> values;
    while (true) {
        const size_t end = text.find('\\');
        std::string_view part = trim(text.substr(0, end));
        if (!part.empty() && part.front() == '+') part.remove_prefix(1);
        double v = 0.0;
        const auto [ptr, ec] = std::from_chars(part.data(), part.data() + part.size(), v);
        if (part.empty() || ec != std::errc() || ptr != part.data() + part.size() ||
            !std::isfinite(v))
            return std::nullopt;
        values.push_back(v);
        if (end == std::string_view::npos) break;
        text.remove_prefix(end + 1);
    }
    if (values.size() != count) return std::nullopt;
    return values;
}

std::optional<double> parseNumber(std::string_view text) {
    const auto v = parseNumbers(text, 1);
    if (!v) return std::nullopt;
    return (*v)[0];
}

std::optional<FileScalar> pixelType(int bitsAllocated, int pixelRepresentation) {
    const bool isSigned = pixelRepresentation == 1;
    switch (bitsAllocated) {
        case 8: return isSigned ? FileScalar::I8 : FileScalar::U8;
        case 16: return isSigned ? FileScalar::I16 : FileScalar::U16;
        case 32: return isSigned ? FileScalar::I32 : FileScalar::U32;
    }
    return std::nullopt;
}

// In the helper: one file's header up to the pixel data; nullopt when it is not an image.
std::optional<DicomHeader> readHeaderHere(const std::string& path) {
    gdcm::Reader reader;
    reader.SetFileName(path.c_str());
    try {
        if (!reader.ReadUpToTag(gdcm::Tag(0x7fe0, 0x0010))) return std::nullopt;
    } catch (const std::exception&) {
        return std::nullopt;  // GDCM throws on some malformed files: not a DICOM image to us
    }
    const gdcm::File& file = reader.GetFile();
    const gdcm::DataSet& ds = file.GetDataSet();
    gdcm::StringFilter filter;
    filter.SetFile(file);
    auto text = [&](uint16_t group, uint16_t element) -> std::string {
        const gdcm::Tag tag(group, element);
        if (!ds.FindDataElement(tag)) return {};
        return std::string(trim(filter.ToString(tag)));
    };
    auto integer = [&](uint16_t group, uint16_t element) -> std::optional<int64_t> {
        const auto v = parseNumber(text(group, element));
        if (!v || *v != std::floor(*v) || std::abs(*v) > 1e15) return std::nullopt;
        return int64_t(*v);
    };
    const auto rows = integer(0x0028, 0x0010), columns = integer(0x0028, 0x0011);
    if (!rows || !columns) return std::nullopt;  // not an image (a DICOMDIR, a report)
    DicomHeader h;
    h.path = path;
    h.rows = uint32_t(std::clamp<int64_t>(*rows, 0, 65535));
    h.columns = uint32_t(std::clamp<int64_t>(*columns, 0, 65535));
    h.seriesUid = text(0x0020, 0x000e);
    h.seriesDescription = text(0x0008, 0x103e);
    h.modality = text(0x0008, 0x0060);
    h.transferSyntax = file.GetHeader().GetDataSetTransferSyntax().GetString()
                           ? file.GetHeader().GetDataSetTransferSyntax().GetString()
                           : "";
    const int64_t samplesPerPixel = integer(0x0028, 0x0002).value_or(1);
    const int64_t bitsAllocated = integer(0x0028, 0x0100).value_or(0);
    const int64_t representation = integer(0x0028, 0x0103).value_or(0);
    const int64_t frames = integer(0x0028, 0x0008).value_or(1);
    h.bitsStored = int(integer(0x0028, 0x0101).value_or(bitsAllocated));
    if (samplesPerPixel != 1)
        h.problem = "has " + std::to_string(samplesPerPixel) +
                    " samples per pixel (colour): only single-channel images are supported";
    else if (frames != 1)
        h.problem = "holds " + std::to_string(frames) +
                    " frames: multi-frame (enhanced) images are not supported";
    if (const auto type = pixelType(int(bitsAllocated), int(representation)))
        h.pixelType = *type;
    else if (h.problem.empty())
        h.problem = "has BitsAllocated " + std::to_string(bitsAllocated) +
                    ": supported are 8, 16 and 32";
    if (const auto p = parseNumbers(text(0x0020, 0x0032), 3)) h.position = glm::dvec3((*p)[0], (*p)[1], (*p)[2]);
    if (const auto o = parseNumbers(text(0x0020, 0x0037), 6)) {
        std::array<double, 6> a;
        std::copy(o->begin(), o->end(), a.begin());
        h.orientation = a;
    }
    if (const auto s = parseNumbers(text(0x0028, 0x0030), 2)) h.pixelSpacing = {(*s)[0], (*s)[1]};
    else if (const auto s2 = parseNumbers(text(0x0018, 0x1164), 2)) h.pixelSpacing = {(*s2)[0], (*s2)[1]};
    h.sliceSpacing = parseNumber(text(0x0018, 0x0088));
    if (!h.sliceSpacing) h.sliceSpacing = parseNumber(text(0x0018, 0x0050));
    h.instanceNumber = integer(0x0020, 0x0013);
    if (const auto slope = parseNumber(text(0x0028, 0x1053))) h.slope = *slope;
    if (const auto intercept = parseNumber(text(0x0028, 0x1052))) h.intercept = *intercept;
    return h;
}

// In the helper: the files a DICOMDIR's records name (ReferencedFileID, relative to its folder).
std::vector<std::string> dicomdirFilesHere(const std::string& path) {
    gdcm::Reader reader;
    reader.SetFileName(path.c_str());
    bool ok = false;
    try {
        ok = reader.Read();
    } catch (const std::exception&) {
    }
    if (!ok) refuse("cannot be read as a DICOMDIR");
    const gdcm::DataSet& ds = reader.GetFile().GetDataSet();
    const gdcm::Tag records(0x0004, 0x1220), fileId(0x0004, 0x1500);
    if (!ds.FindDataElement(records)) refuse("is a DICOMDIR without records");
    const gdcm::SmartPointer<gdcm::SequenceOfItems> items = ds.GetDataElement(records).GetValueAsSQ();
    if (!items) refuse("is a DICOMDIR whose records cannot be read");
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    std::vector<std::string> files;
    gdcm::StringFilter filter;
    filter.SetFile(reader.GetFile());
    for (gdcm::SequenceOfItems::SizeType i = 1; i <= items->GetNumberOfItems(); ++i) {
        const gdcm::DataSet& record = items->GetItem(i).GetNestedDataSet();
        if (!record.FindDataElement(fileId)) continue;
        std::string id(trim(filter.ToString(record.GetDataElement(fileId))));
        if (id.empty() || id.find('\0') != std::string::npos) continue;
        std::filesystem::path relative;
        for (size_t start = 0; start <= id.size();) {
            const size_t end = std::min(id.find('\\', start), id.size());
            const std::string part(trim(std::string_view(id).substr(start, end - start)));
            if (part == ".." || part == ".")
                refuse("a record names a file outside its folder: " + id);
            if (!part.empty()) relative /= part;
            start = end + 1;
        }
        files.push_back((folder / relative).string());
    }
    if (files.empty()) refuse("is a DICOMDIR that names no file");
    return files;
}

// In the helper: decodes one file's pixel data into `samples`; returns "" or what is wrong.
std::string decodeHere(const std::string& path, const DicomHeader& h, std::string& samples) {
    gdcm::ImageReader reader;
    reader.SetFileName(path.c_str());
    if (!reader.Read())
        return "cannot be read as a DICOM image (transfer syntax " + h.transferSyntax + ")";
    const gdcm::Image& image = reader.GetImage();
    const gdcm::PixelFormat& format = image.GetPixelFormat();
    const unsigned bits = unsigned(fileScalarSize(h.pixelType) * 8);
    if (image.GetDimension(0) != h.columns || image.GetDimension(1) != h.rows ||
        (image.GetNumberOfDimensions() > 2 && image.GetDimension(2) != 1) ||
        format.GetSamplesPerPixel() != 1 || format.GetBitsAllocated() != bits)
        return "its pixel data is not the " + std::to_string(h.columns) + " x " +
               std::to_string(h.rows) + " single-channel " + std::to_string(bits) +
               "-bit image its header describes";
    const size_t bytes = size_t(h.rows) * h.columns * (bits / 8);
    // Native data is copied as it is: it must hold the whole image (the parent checked the file
    // as it saw it; this is what GDCM parsed, inflated if the data set was deflated).
    if (const gdcm::ByteValue* native = image.GetDataElement().GetByteValue();
        native && native->GetLength() < bytes)
        return "its pixel data holds " + std::to_string(native->GetLength()) + " bytes where " +
               std::to_string(h.columns) + " x " + std::to_string(h.rows) + " x " +
               std::to_string(bits / 8) + " = " + std::to_string(bytes) + " are needed";
    if (!image.GetDataElement().GetByteValue() && !image.GetDataElement().GetSequenceOfFragments())
        return "its pixel data is neither native nor encapsulated";
    if (image.GetBufferLength() != bytes)
        return "its pixel data is " + std::to_string(image.GetBufferLength()) + " bytes where " +
               std::to_string(bytes) + " are needed";
    samples.resize(bytes);
    if (!image.GetBuffer(samples.data())) {
        const char* name = image.GetTransferSyntax().GetString();
        return "its pixel data (transfer syntax " + h.transferSyntax + ", " +
               (name ? name : "unknown") + ") cannot be decoded by this GDCM, or is damaged";
    }
    return "";
}

// The helper's loop. A request: kind ('H' header, 'D' DICOMDIR, 'P' pixels), path, body. A
// reply: status (0 ok, 1 error message, 2 none) and body. Ends when the socket closes.
void serve(int fd) {
    gdcm::Trace::SetDebug(false);
    gdcm::Trace::SetWarning(false);
    gdcm::Trace::SetError(false);
    for (;;) {
        char kind = 0;
        uint64_t sizes[2] = {0, 0};
        if (!receiveAll(fd, &kind, 1) || !receiveAll(fd, sizes, sizeof(sizes))) return;
        std::string path(size_t(sizes[0]), '\0'), request(size_t(sizes[1]), '\0');
        if (!receiveAll(fd, path.data(), path.size()) ||
            !receiveAll(fd, request.data(), request.size()))
            return;
        uint8_t status = 0;
        std::string body;
        try {
            if (kind == 'H') {
                const std::optional<DicomHeader> h = readHeaderHere(path);
                if (!h) status = 2;
                else {
                    WireWriter w;
                    putDicomHeader(w, *h);
                    body = w.bytes();
                }
            } else if (kind == 'D') {
                WireWriter w;
                const std::vector<std::string> files = dicomdirFilesHere(path);
                w.put(uint64_t(files.size()));
                for (const std::string& f : files) w.put(f);
                body = w.bytes();
            } else {
                const std::string error = decodeHere(path, getDicomHeader(request, path), body);
                if (!error.empty()) {
                    status = 1;
                    body = error;
                }
            }
        } catch (const Refusal& e) {
            status = 1;
            body = e.what();  // without the path: the parent adds it
        } catch (const std::exception& e) {
            status = 1;
            body = std::string("GDCM failed on it: ") + e.what();
        }
        if (!sendReply(fd, status, body)) return;
    }
}

}  // namespace
}  // namespace vdiso

extern "C" int vdiso_gdcm_serve(int fd) {
    try {
        vdiso::serve(fd);
    } catch (...) {
        // Only allocation can fail outside serve's own handlers; the parent sees the socket
        // close and reports the request as failed.
    }
    return 0;
}
