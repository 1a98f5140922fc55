#include "io/readers/dicom_reader.h"


#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>
#include <utility>

#include "core/interrupt.h"
#include "io/readers/dicom_series.h"
#include "io/readers/dicom_structure.h"
#include "io/error.h"
#include "io/readers/file_list.h"
#include "io/readers/file_names.h"
#include "io/readers/gdcm_process.h"
#include "io/readers/jpeg_frame_header.h"
#include "io/readers/sample_decode.h"

namespace vdiso {
namespace {

// A file's header, read by GDCM in the helper; nullopt when it is not a DICOM image. Throws
// IoError for a damaged file: its structure is checked first (io/readers/dicom_structure.h), through
// the pixel data, whose basic offset table GDCM reads with the header (fuzz_dicom: a table
// claiming 3.7 GB in a 904-byte file), and GDCM is not asked to read one without pixel data (a
// report, a DICOMDIR, or a file cut off before its pixels).
std::optional<DicomHeader> readDicomHeader(GdcmProcess& gdcm, const std::string& path) {
    const DicomStructure structure = checkDicomStructure(path, true);
    const bool deflated = structure.transferSyntax == kDeflatedTransferSyntax;
    if (!structure.hasPixelData && !deflated) return std::nullopt;
    return gdcm.readHeader(path);
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

// JPEG baseline, extended, lossless (14 and 14 SV1) and JPEG-LS: a frame header (SOFn, SOF55)
// in the first fragment says what the decoder will make.
bool isJpegSyntax(const std::string& uid) {
    for (const char* jpeg : {"1.2.840.10008.1.2.4.50", "1.2.840.10008.1.2.4.51", "1.2.840.10008.1.2.4.57",
                             "1.2.840.10008.1.2.4.70", "1.2.840.10008.1.2.4.80", "1.2.840.10008.1.2.4.81"})
        if (uid == jpeg) return true;
    return false;
}

// The first fragment's frame header must describe the image the DICOM header does (GDCM's JPEG
// codec trusts it, and crashed on 250-bit samples: fuzz_dicom).
void checkJpegFrame(const DicomHeader& h, const DicomStructure& s, uint64_t bitsAllocated) {
    std::vector<unsigned char> head(size_t(std::min<uint64_t>(s.firstFragmentBytes, 65536)));
    std::ifstream in(h.path, std::ios::binary);
    if (!in.seekg(std::streamoff(s.firstFragmentOffset)).read(reinterpret_cast<char*>(head.data()),
                                                            std::streamsize(head.size())))
        throwIoError(h.path, "cannot read its first pixel data fragment");
    const std::optional<JpegFrameHeader> f = readJpegFrameHeader(head.data(), head.size());
    if (!f)
        throwIoError(h.path, "its JPEG pixel data (transfer syntax " + s.transferSyntax +
                                 ") has no frame header in its first fragment");
    if (f->precision < 2 || uint64_t(f->precision) > bitsAllocated || f->components != 1 ||
        f->columns != h.columns || (f->lines != h.rows && f->lines != 0))
        throwIoError(h.path, "its JPEG data describes a " + std::to_string(f->columns) + " x " +
                                 std::to_string(f->lines) + " image of " + std::to_string(f->precision) +
                                 "-bit samples in " + std::to_string(f->components) +
                                 " component(s), where its header says " + std::to_string(h.columns) +
                                 " x " + std::to_string(h.rows) + ", single-channel, BitsAllocated " +
                                 std::to_string(bitsAllocated));
}

// Refuses pixel data that cannot hold what the header promises, before GDCM decodes it: native
// data shorter than Rows x Columns x BitsAllocated / 8 (GDCM would copy the rest from beyond
// its buffer), encapsulated data without a fragment. A deflated data set is checked in the
// helper, after GDCM inflated it (io/gdcm_module).
void checkPixelData(const DicomHeader& h, const DicomStructure& s) {
    if (s.transferSyntax == kDeflatedTransferSyntax) return;
    const uint64_t bits = uint64_t(fileScalarSize(h.pixelType)) * 8;
    const uint64_t need = nativePixelBytes(h.rows, h.columns, 1, bits, 1);
    if (s.encapsulated && s.fragments == 0)
        throwIoError(h.path, "its encapsulated pixel data (transfer syntax " + s.transferSyntax +
                                 ") has no fragment after its offset table");
    if (s.encapsulated && isJpegSyntax(s.transferSyntax)) checkJpegFrame(h, s, bits);
    if (!s.encapsulated && s.pixelBytes < need)
        throwIoError(h.path, "its pixel data holds " + std::to_string(s.pixelBytes) +
                                 " bytes where Rows x Columns x BitsAllocated/8 (" +
                                 std::to_string(h.rows) + " x " + std::to_string(h.columns) +
                                 " x " + std::to_string(bits / 8) + ") needs " +
                                 std::to_string(need));
}

class DicomSliceReader final : public SliceReader {
public:
    DicomSliceReader(std::string name, DicomVolume volume, std::unique_ptr<GdcmProcess> gdcm)
        : mName(std::move(name)), mVolume(std::move(volume)), mGdcm(std::move(gdcm)) {}

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

    // Files passed over are not opened.
    void skip(int64_t count) override {
        if (count < 0 || count > int64_t(mVolume.slices.size()) - mNext)
            throwIoError(mName, "has fewer slices than asked for");
        mNext += count;
    }

    std::string name() const override { return mName; }
    std::vector<std::string> files() const override {
        std::vector<std::string> paths;
        for (const DicomHeader& h : mVolume.slices) paths.push_back(h.path);
        return paths;
    }

private:
    void readSlice(const DicomHeader& h, unsigned char* dst) {
        // Also when it was sound at open: it may have changed.
        checkPixelData(h, checkDicomStructure(h.path, true));
        const size_t samples = size_t(h.rows) * h.columns;
        mScratch.resize(samples * fileScalarSize(h.pixelType));
        mGdcm->decodePixels(h, mScratch.data());
        decodeSamples(mScratch.data(), h.pixelType, false, samples, dst, mVolume.info.type,
                      mVolume.scaled, h.slope, h.intercept);
    }

    std::string mName;
    DicomVolume mVolume;
    std::unique_ptr<GdcmProcess> mGdcm;  // the one that read the headers
    std::vector<unsigned char> mScratch;
    int64_t mNext = 0;
};

// Reads the headers of `files`; with `skipOthers`, files that are not DICOM images are passed
// over (a folder's other files), else refused.
std::vector<DicomHeader> readHeaders(GdcmProcess& gdcm, const std::vector<std::string>& files,
                                     bool skipOthers) {
    std::vector<DicomHeader> headers;
    for (size_t i = 0; i < files.size(); ++i) {
        if ((i & 63) == 63) throwIfInterrupted(files[i]);
        const std::string& f = files[i];
        // In a folder, only Part 10 files (DICM at byte 128) are DICOM; a damaged one is an
        // error, not passed over, since leaving it out would make a gap.
        if (skipOthers && !hasDicomMagic(f)) continue;
        std::optional<DicomHeader> h = readDicomHeader(gdcm, f);
        if (!h) {
            if (skipOthers) continue;
            throwIoError(f, "is not a DICOM image");
        }
        headers.push_back(std::move(*h));
    }
    return headers;
}

std::unique_ptr<SliceReader> openSeries(const std::string& name, std::vector<DicomHeader> headers,
                                        const std::string& seriesUid,
                                        std::unique_ptr<GdcmProcess> gdcm) {
    std::vector<DicomHeader> series = selectDicomSeries(std::move(headers), seriesUid, name);
    for (const DicomHeader& h : series)
        if (!h.problem.empty()) throwIoError(h.path, h.problem);
    return std::make_unique<DicomSliceReader>(name, arrangeDicomSeries(std::move(series), name),
                                              std::move(gdcm));
}

}  // namespace

bool hasDicomMagic(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char b[4] = {};
    return in.seekg(128) && in.read(b, 4) && std::string_view(b, 4) == "DICM";
}

std::unique_ptr<SliceReader> openDicomImage(const std::string& path) {
    auto gdcm = std::make_unique<GdcmProcess>();
    std::vector<DicomHeader> headers = readHeaders(*gdcm, {path}, false);
    if (!headers.front().problem.empty()) throwIoError(path, headers.front().problem);
    return std::make_unique<DicomSliceReader>(path, arrangeDicomSeries(std::move(headers), path, 1),
                                              std::move(gdcm));
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
    if (files.empty()) throw IoError("no DICOM files given");
    auto gdcm = std::make_unique<GdcmProcess>();
    std::vector<DicomHeader> headers = readHeaders(*gdcm, files, false);
    return openSeries(files.front(), std::move(headers), seriesUid, std::move(gdcm));
}

std::unique_ptr<SliceReader> openDicomVolume(const std::string& path, const std::string& seriesUid) {
    auto gdcm = std::make_unique<GdcmProcess>();
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        std::vector<DicomHeader> headers = readHeaders(*gdcm, filesUnder(path), true);
        return openSeries(path, std::move(headers), seriesUid, std::move(gdcm));
    }
    if (isDicomdirName(path)) {
        checkDicomStructure(path, true);
        std::vector<DicomHeader> headers = readHeaders(*gdcm, gdcm->dicomdirFiles(path), false);
        return openSeries(path, std::move(headers), seriesUid, std::move(gdcm));
    }
    // One file: the series it belongs to, from the files beside it.
    if (!std::filesystem::exists(path, ec)) throwIoError(path, "no such file");
    const std::optional<DicomHeader> h = readDicomHeader(*gdcm, path);
    if (!h) throwIoError(path, "is not a DICOM image");
    const std::string folder = std::filesystem::path(path).parent_path().string();
    std::vector<DicomHeader> headers = readHeaders(*gdcm, listFolder(folder.empty() ? "." : folder, {}), true);
    return openSeries(path, std::move(headers), seriesUid.empty() ? h->seriesUid : seriesUid,
                      std::move(gdcm));
}

}  // namespace vdiso
