#include "io/readers/dicom_structure.h"

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>

#include "io/readers/byte_stream.h"
#include "io/error.h"

namespace vdiso {
namespace {

constexpr uint32_t kUndefinedLength = 0xffffffffu;
constexpr int kMaxDepth = 64;
constexpr uint16_t kItemGroup = 0xfffe;
constexpr uint16_t kItem = 0xe000, kItemEnd = 0xe00d, kSequenceEnd = 0xe0dd;

struct Encoding {
    bool explicitVR = true;
    bool bigEndian = false;
};

struct Element {
    uint16_t group = 0, element = 0;
    char vr[2] = {0, 0};
    uint32_t length = 0;
    uint64_t value = 0;  // where the value starts
    bool isVR(const char* name) const { return vr[0] == name[0] && vr[1] == name[1]; }
};

std::string tagText(uint16_t group, uint16_t element) {
    char text[16];
    std::snprintf(text, sizeof(text), "(%04X,%04X)", group, element);
    return text;
}

// VRs whose explicit encoding has two reserved bytes and a 32-bit length.
bool hasLongLength(const char vr[2]) {
    static const char* const kLong[] = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ",
                                        "SV", "UC", "UN", "UR", "UT", "UV"};
    for (const char* v : kLong)
        if (vr[0] == v[0] && vr[1] == v[1]) return true;
    return false;
}

bool isKnownVR(const char vr[2]) {
    static const char* const kVRs[] = {"AE", "AS", "AT", "CS", "DA", "DS", "DT", "FL", "FD",
                                       "IS", "LO", "LT", "OB", "OD", "OF", "OL", "OV", "OW",
                                       "PN", "SH", "SL", "SQ", "SS", "ST", "SV", "TM", "UC",
                                       "UI", "UL", "UN", "UR", "US", "UT", "UV"};
    for (const char* v : kVRs)
        if (vr[0] == v[0] && vr[1] == v[1]) return true;
    return false;
}

class Walker {
public:
    Walker(const std::string& path, bool throughPixelData)
        : mPath(path), mIn(path, std::ios::binary), mSize(fileSize(path)),
          mThroughPixelData(throughPixelData) {
        if (!mIn) throwIoError(path, "cannot be opened");
    }

    DicomStructure walk() {
        char magic[4] = {};
        if (mSize < 132 || !readAt(128, magic, 4) || std::memcmp(magic, "DICM", 4) != 0)
            throwIoError(mPath, "is not a DICOM Part 10 file (no DICM signature at byte 128)");
        DicomStructure s;
        // The meta header: explicit VR little endian, group 0002 only. GDCM falls back to its
        // group length (0002,0000) when the elements do not parse, so that must agree too.
        uint64_t at = 132;
        const Encoding meta;
        std::optional<uint64_t> groupEnd;
        while (at < mSize) {
            uint16_t group = 0;
            if (!readNumber(at, 2, meta, group) || group != 0x0002) break;
            const Element e = readElement(at, mSize, meta);
            if (e.length == kUndefinedLength) fail(at, e, "has an undefined length in the meta header");
            if (e.element == 0x0000) {
                uint32_t length = 0;
                if (at != 132 || !e.isVR("UL") || e.length != 4 || !readNumber(e.value, 4, meta, length))
                    fail(at, e, "is not the meta header's group length (UL, first)");
                groupEnd = e.value + 4 + uint64_t(length);
            }
            if (e.element == 0x0010) {
                std::string uid(e.length, '\0');
                readAt(e.value, uid.data(), e.length);
                while (!uid.empty() && (uid.back() == '\0' || uid.back() == ' ')) uid.pop_back();
                s.transferSyntax = uid;
            }
            at = e.value + e.length;
        }
        if (groupEnd && *groupEnd != at)
            throwIoError(mPath, "its meta header's group length (0002,0000) says it ends at byte " +
                                    std::to_string(*groupEnd) + ", its elements end at " +
                                    std::to_string(at));
        if (s.transferSyntax.empty())
            throwIoError(mPath, "its meta header names no transfer syntax (0002,0010)");
        if (s.transferSyntax == kDeflatedTransferSyntax) return s;  // deflated: GDCM inflates
        Encoding data;
        data.explicitVR = s.transferSyntax != "1.2.840.10008.1.2";
        data.bigEndian = s.transferSyntax == "1.2.840.10008.1.2.2";
        walkDataSet(at, mSize, false, data, 0, true);
        mPixels.transferSyntax = s.transferSyntax;
        mPixels.hasPixelData = mSawPixelData;
        return mPixels;
    }

private:
    bool readAt(uint64_t offset, void* dst, size_t n) {
        if (offset > mSize || n > mSize - offset) return false;
        mIn.clear();
        return bool(mIn.seekg(std::streamoff(offset)).read(static_cast<char*>(dst), std::streamsize(n)));
    }

    template <class T>
    bool readNumber(uint64_t offset, size_t n, const Encoding& enc, T& value) {
        unsigned char b[4] = {};
        if (!readAt(offset, b, n)) return false;
        uint32_t v = 0;
        for (size_t i = 0; i < n; ++i) {
            const size_t k = enc.bigEndian ? i : n - 1 - i;
            v = (v << 8) | b[k];
        }
        value = T(v);
        return true;
    }

    [[noreturn]] void fail(uint64_t offset, const Element& e, const std::string& what) {
        throwIoError(mPath, "element " + tagText(e.group, e.element) + " at byte " +
                                std::to_string(offset) + " " + what);
    }

    // The element header at `at`, whose value must end by `end` unless its length is undefined.
    Element readElement(uint64_t at, uint64_t end, const Encoding& enc) {
        Element e;
        if (at + 8 > end || !readNumber(at, 2, enc, e.group) || !readNumber(at + 2, 2, enc, e.element))
            throwIoError(mPath, "is cut off in the element header at byte " + std::to_string(at));
        const bool itemTag = e.group == kItemGroup;
        if (enc.explicitVR && !itemTag) {
            readAt(at + 4, e.vr, 2);
            if (!isKnownVR(e.vr)) fail(at, e, "has an unknown VR");
            if (hasLongLength(e.vr)) {
                if (at + 12 > end || !readNumber(at + 8, 4, enc, e.length))
                    fail(at, e, "is cut off in its header");
                e.value = at + 12;
            } else {
                readNumber(at + 6, 2, enc, e.length);
                e.value = at + 8;
            }
        } else {
            readNumber(at + 4, 4, enc, e.length);
            e.value = at + 8;
        }
        if (e.length != kUndefinedLength && (e.value > end || e.length > end - e.value))
            fail(at, e, "has a length of " + std::to_string(e.length) + " bytes, past the end of " +
                            (end == mSize ? std::string("the file") : "what contains it") +
                            " (" + std::to_string(end) + ")");
        return e;
    }

    // Walks elements from `at` to `end` (or, with `untilItemEnd`, to an item delimiter); returns
    // where the walk stopped.
    uint64_t walkDataSet(uint64_t at, uint64_t end, bool untilItemEnd, const Encoding& enc,
                         int depth, bool topLevel) {
        if (depth > kMaxDepth)
            throwIoError(mPath, "nests sequences more than " + std::to_string(kMaxDepth) +
                                    " deep at byte " + std::to_string(at));
        while (at < end) {
            const Element e = readElement(at, end, enc);
            if (e.group == kItemGroup) {
                if (e.element == kItemEnd && untilItemEnd) return e.value;
                fail(at, e, "is an item tag where a data element belongs");
            }
            if (topLevel && e.group == 0x7fe0 && e.element == 0x0010) {
                mSawPixelData = true;
                if (!mThroughPixelData) return at;
                mPixels.encapsulated = e.length == kUndefinedLength;
                if (!mPixels.encapsulated) mPixels.pixelBytes = e.length;
            }
            if (e.length != kUndefinedLength) {
                if (enc.explicitVR && e.isVR("SQ"))
                    walkItems(e.value, e.value + e.length, false, enc, depth + 1);
                at = e.value + e.length;
            } else if (e.group == 0x7fe0 && e.element == 0x0010 && enc.explicitVR) {
                at = walkFragments(e.value, end, topLevel);
            } else if (!enc.explicitVR || e.isVR("SQ")) {
                at = walkItems(e.value, end, true, enc, depth + 1);
            } else if (e.isVR("UN")) {
                // An undefined-length UN holds a sequence in implicit VR little endian.
                at = walkItems(e.value, end, true, Encoding{false, false}, depth + 1);
            } else {
                fail(at, e, std::string("has an undefined length, which VR ") + e.vr[0] + e.vr[1] +
                                " cannot have");
            }
        }
        if (untilItemEnd) throwIoError(mPath, "ends inside an item of undefined length");
        return at;
    }

    // Items of a sequence from `at`: to `end` for a defined length, else to the sequence end.
    uint64_t walkItems(uint64_t at, uint64_t end, bool untilSequenceEnd, const Encoding& enc,
                       int depth) {
        while (at < end) {
            const Element item = readElement(at, end, Encoding{false, enc.bigEndian});
            if (item.group != kItemGroup) fail(at, item, "stands where a sequence item belongs");
            if (item.element == kSequenceEnd && untilSequenceEnd) return item.value;
            if (item.element != kItem) fail(at, item, "stands where a sequence item belongs");
            if (item.length == kUndefinedLength)
                at = walkDataSet(item.value, end, true, enc, depth, false);
            else
                at = walkDataSet(item.value, item.value + item.length, false, enc, depth, false);
        }
        if (untilSequenceEnd) throwIoError(mPath, "ends inside a sequence of undefined length");
        return at;
    }

    // Encapsulated pixel data: items of defined length up to the sequence end, the first the
    // basic offset table (empty, or a 32-bit offset per frame). Counted for the top level.
    uint64_t walkFragments(uint64_t at, uint64_t end, bool topLevel) {
        const Encoding little{false, false};
        bool first = true;
        while (at < end) {
            const Element item = readElement(at, end, little);
            if (item.group == kItemGroup && item.element == kSequenceEnd) {
                if (first) fail(at, item, "ends encapsulated pixel data that has no basic offset table");
                return item.value;
            }
            if (item.group != kItemGroup || item.element != kItem ||
                item.length == kUndefinedLength)
                fail(at, item, "stands where a pixel data fragment belongs");
            if (first && item.length % 4 != 0)
                fail(at, item, "is a basic offset table of " + std::to_string(item.length) +
                                   " bytes, not a whole number of 32-bit offsets");
            if (topLevel && first) mPixels.offsetTableBytes = item.length;
            else if (topLevel) {
                if (mPixels.fragments == 0) {
                    mPixels.firstFragmentOffset = item.value;
                    mPixels.firstFragmentBytes = item.length;
                }
                ++mPixels.fragments;
                mPixels.pixelBytes += item.length;
            }
            first = false;
            at = item.value + item.length;
        }
        throwIoError(mPath, "ends inside its encapsulated pixel data");
    }

    std::string mPath;
    std::ifstream mIn;
    uint64_t mSize;
    bool mThroughPixelData;
    bool mSawPixelData = false;
    DicomStructure mPixels;  // the pixel data's fields as the walk finds them; then the result
};

}  // namespace

uint64_t nativePixelBytes(uint64_t rows, uint64_t columns, uint64_t samplesPerPixel,
                          uint64_t bitsAllocated, uint64_t frames) {
    if (rows > 65535 || columns > 65535 || samplesPerPixel > 4 || bitsAllocated > 64 ||
        bitsAllocated % 8 != 0 || frames > (uint64_t(1) << 31))
        return 0;
    return rows * columns * samplesPerPixel * (bitsAllocated / 8) * frames;
}

DicomStructure checkDicomStructure(const std::string& path, bool throughPixelData) {
    return Walker(path, throughPixelData).walk();
}

}  // namespace vdiso
