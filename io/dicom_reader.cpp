#include "io/dicom_reader.h"

#include <gdcmDataSet.h>
#include <gdcmFile.h>
#include <gdcmReader.h>
#include <gdcmSequenceOfItems.h>
#include <gdcmStringFilter.h>
#include <gdcmTrace.h>
#include <gdcmTransferSyntax.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>
#include <utility>

#include "core/interrupt.h"
#include "io/dicom_decoder.h"
#include "io/dicom_series.h"
#include "io/dicom_structure.h"
#include "io/error.h"
#include "io/file_list.h"
#include "io/file_names.h"
#include "io/sample_decode.h"

namespace vdiso {
namespace {

// GDCM prints warnings and errors to std::cerr unless told not to; our errors are exceptions.
void silenceGdcm() {
    static const bool silenced = [] {
        gdcm::Trace::SetDebug(false);
        gdcm::Trace::SetWarning(false);
        gdcm::Trace::SetError(false);
        return true;
    }();
    (void)silenced;
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

// Reads one file's header up to the pixel data; nullopt when it is not a DICOM image. Throws
// IoError for a damaged file (checked before GDCM sees it, io/dicom_structure.h).
std::optional<DicomHeader> readDicomHeader(const std::string& path) {
    const DicomStructure structure = checkDicomStructure(path, false);
    // GDCM is not asked to read past the end of what was checked: without pixel data it is
    // not an image to us (a report, a DICOMDIR, or a file cut off before its pixels).
    const bool deflated = structure.transferSyntax == "1.2.840.10008.1.2.1.99";
    if (!structure.hasPixelData && !deflated) return std::nullopt;
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

// The files a DICOMDIR's records name (ReferencedFileID, relative to its folder).
std::vector<std::string> dicomdirFiles(const std::string& path) {
    checkDicomStructure(path, true);
    gdcm::Reader reader;
    reader.SetFileName(path.c_str());
    bool ok = false;
    try {
        ok = reader.Read();
    } catch (const std::exception&) {
    }
    if (!ok) throwIoError(path, "cannot be read as a DICOMDIR");
    const gdcm::DataSet& ds = reader.GetFile().GetDataSet();
    const gdcm::Tag records(0x0004, 0x1220), fileId(0x0004, 0x1500);
    if (!ds.FindDataElement(records)) throwIoError(path, "is a DICOMDIR without records");
    const gdcm::SmartPointer<gdcm::SequenceOfItems> items = ds.GetDataElement(records).GetValueAsSQ();
    if (!items) throwIoError(path, "is a DICOMDIR whose records cannot be read");
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
                throwIoError(path, "a record names a file outside its folder: " + id);
            if (!part.empty()) relative /= part;
            start = end + 1;
        }
        files.push_back((folder / relative).string());
    }
    if (files.empty()) throwIoError(path, "is a DICOMDIR that names no file");
    return files;
}

bool isDicomdirName(const std::string& path) {
    const std::string name = std::filesystem::path(path).filename().string();
    return name.size() == 8 && endsWithIgnoreCase(name, "DICOMDIR");
}

// Every regular file under `dir` (subfolders too, hidden ones skipped), in natural order.
std::vector<std::string> filesUnder(const std::string& dir) {
    std::vector<std::string> files;
    std::error_code ec;
    auto it = std::filesystem::recursive_directory_iterator(
        dir, std::filesystem::directory_options::skip_permission_denied, ec);
    if (ec) throwIoError(dir, "cannot list the folder: " + ec.message());
    for (; it != std::filesystem::recursive_directory_iterator(); it.increment(ec)) {
        if (ec) throwIoError(dir, "cannot list the folder: " + ec.message());
        const std::string name = it->path().filename().string();
        if (!name.empty() && name[0] == '.') {
            if (it->is_directory(ec)) it.disable_recursion_pending();
            continue;
        }
        if (it->is_regular_file(ec)) files.push_back(it->path().string());
        if ((files.size() & 1023) == 1023) throwIfInterrupted(dir);
    }
    std::sort(files.begin(), files.end(), naturalLess);
    return files;
}

class DicomSliceReader final : public SliceReader {
public:
    DicomSliceReader(std::string name, DicomVolume volume)
        : mName(std::move(name)), mVolume(std::move(volume)) {}

    const VolumeInfo& info() const override { return mVolume.info; }

    void read(void* dst, int64_t count) override {
        auto* out = static_cast<unsigned char*>(dst);
        const VolumeInfo& info = mVolume.info;
        const size_t sliceBytes = size_t(info.sliceSamples()) * scalarSize(info.type);
        for (int64_t s = 0; s < count; ++s, ++mNext) {
            if (mNext >= int64_t(mVolume.slices.size()))
                throwIoError(mName, "has fewer slices than asked for");
            throwIfInterrupted(mName);
            readSlice(mVolume.slices[size_t(mNext)], out + size_t(s) * sliceBytes);
        }
    }

    std::string name() const override { return mName; }
    std::vector<std::string> files() const override {
        std::vector<std::string> paths;
        for (const DicomHeader& h : mVolume.slices) paths.push_back(h.path);
        return paths;
    }

private:
    void readSlice(const DicomHeader& h, unsigned char* dst) {
        checkDicomStructure(h.path, true);  // also when it was sound at open: it may have changed
        DicomPixelRequest request;
        request.path = h.path;
        request.transferSyntax = h.transferSyntax;
        request.rows = h.rows;
        request.columns = h.columns;
        request.bitsAllocated = uint32_t(fileScalarSize(h.pixelType) * 8);
        const size_t samples = size_t(h.rows) * h.columns;
        mScratch.resize(samples * fileScalarSize(h.pixelType));
        mDecoder.decode(request, mScratch.data());
        decodeSamples(mScratch.data(), h.pixelType, false, samples, dst, mVolume.info.type,
                      mVolume.scaled, h.slope, h.intercept);
    }

    std::string mName;
    DicomVolume mVolume;
    std::vector<unsigned char> mScratch;
    DicomPixelDecoder mDecoder;
    int64_t mNext = 0;
};

// Reads the headers of `files`; with `skipOthers`, files that are not DICOM images are passed
// over (a folder's other files), else refused.
std::vector<DicomHeader> readHeaders(const std::vector<std::string>& files, bool skipOthers) {
    std::vector<DicomHeader> headers;
    for (size_t i = 0; i < files.size(); ++i) {
        if ((i & 63) == 63) throwIfInterrupted(files[i]);
        const std::string& f = files[i];
        // In a folder, only Part 10 files (DICM at byte 128) are DICOM; a damaged one is an
        // error, not passed over, since leaving it out would make a gap.
        if (skipOthers && !hasDicomMagic(f)) continue;
        std::optional<DicomHeader> h = readDicomHeader(f);
        if (!h) {
            if (skipOthers) continue;
            throwIoError(f, "is not a DICOM image");
        }
        headers.push_back(std::move(*h));
    }
    return headers;
}

std::unique_ptr<SliceReader> openSeries(const std::string& name, std::vector<DicomHeader> headers,
                                        const std::string& seriesUid) {
    std::vector<DicomHeader> series = selectDicomSeries(std::move(headers), seriesUid, name);
    for (const DicomHeader& h : series)
        if (!h.problem.empty()) throwIoError(h.path, h.problem);
    return std::make_unique<DicomSliceReader>(name, arrangeDicomSeries(std::move(series), name));
}

}  // namespace

bool hasDicomMagic(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char b[4] = {};
    return in.seekg(128) && in.read(b, 4) && std::string_view(b, 4) == "DICM";
}

std::unique_ptr<SliceReader> openDicomImage(const std::string& path) {
    silenceGdcm();
    std::vector<DicomHeader> headers = readHeaders({path}, false);
    if (!headers.front().problem.empty()) throwIoError(path, headers.front().problem);
    return std::make_unique<DicomSliceReader>(path, arrangeDicomSeries(std::move(headers), path, 1));
}

bool looksLikeDicomFolder(const std::string& dir) {
    std::error_code ec;
    auto it = std::filesystem::recursive_directory_iterator(
        dir, std::filesystem::directory_options::skip_permission_denied, ec);
    int looked = 0;
    for (; !ec && it != std::filesystem::recursive_directory_iterator() && looked < 64;
         it.increment(ec)) {
        if (!it->is_regular_file(ec)) continue;
        ++looked;
        const std::string p = it->path().string();
        if (isDicomdirName(p) || hasDicomMagic(p)) return true;
    }
    return false;
}

std::unique_ptr<SliceReader> openDicomFiles(const std::vector<std::string>& files,
                                            const std::string& seriesUid) {
    silenceGdcm();
    if (files.empty()) throw IoError("no DICOM files given");
    return openSeries(files.front(), readHeaders(files, false), seriesUid);
}

std::unique_ptr<SliceReader> openDicomVolume(const std::string& path, const std::string& seriesUid) {
    silenceGdcm();
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        return openSeries(path, readHeaders(filesUnder(path), true), seriesUid);
    if (isDicomdirName(path)) return openSeries(path, readHeaders(dicomdirFiles(path), false), seriesUid);
    // One file: the series it belongs to, from the files beside it.
    const std::optional<DicomHeader> h = readDicomHeader(path);
    if (!h) {
        if (!std::filesystem::exists(path, ec)) throwIoError(path, "no such file");
        throwIoError(path, "is not a DICOM image");
    }
    const std::string folder = std::filesystem::path(path).parent_path().string();
    const std::vector<std::string> beside = listFolder(folder.empty() ? "." : folder, {});
    return openSeries(path, readHeaders(beside, true), seriesUid.empty() ? h->seriesUid : seriesUid);
}

}  // namespace vdiso
