#include "io/readers/isolated_reader.h"

#include <stdexcept>
#include <vector>

#include "core/interrupt.h"
#include "io/error.h"
#include "io/readers/helper_process.h"

namespace vdiso {
namespace {

// In the helper: opens the reader, describes it, then serves 'R' (read N slices, each sent as
// its own reply), 'S' (skip N slices, one reply) and 'F' (finish) until the socket closes.
void serveReader(int fd, const std::function<std::unique_ptr<SliceReader>()>& open) {
    std::unique_ptr<SliceReader> reader;
    try {
        reader = open();
    } catch (const std::exception& e) {
        sendReply(fd, 1, e.what());
        return;
    }
    liftMemoryBound();
    const VolumeInfo& info = reader->info();
    WireWriter w;
    w.put(info.dims).put(uint8_t(info.type)).put(info.spacing).put(info.origin).put(reader->name());
    w.put(uint8_t(info.hasOrientation)).put(info.direction[0]).put(info.direction[1]).put(info.direction[2]);
    const std::vector<std::string> files = reader->files();
    w.put(uint64_t(files.size()));
    for (const std::string& f : files) w.put(f);
    if (!sendReply(fd, 0, w.bytes())) return;
    std::string slice;
    for (;;) {
        char command = 0;
        uint64_t count = 0;
        if (!receiveAll(fd, &command, 1) || !receiveAll(fd, &count, sizeof(count))) return;
        try {
            if (command == 'F' || command == 'S') {
                if (command == 'F') reader->finish();
                else reader->skip(int64_t(count));
                if (!sendReply(fd, 0, "")) return;
                continue;
            }
            slice.resize(size_t(info.sliceSamples()) * scalarSize(info.type));
            for (uint64_t s = 0; s < count; ++s) {
                reader->read(slice.data(), 1);
                if (!sendReply(fd, 0, slice)) return;
            }
        } catch (const std::exception& e) {
            if (!sendReply(fd, 1, e.what())) return;
        }
    }
}

class IsolatedReader final : public SliceReader {
public:
    IsolatedReader(const std::string& name, const std::string& library,
                   const std::function<std::unique_ptr<SliceReader>()>& open)
        : mName(name), mLibrary(library) {
        mHelper.start(name, [&open](int fd) { serveReader(fd, open); });
        std::string body;
        const uint8_t status = reply(body, "opening it");
        if (status != 0) throw IoError(body);
        WireReader r(body);
        uint8_t type = 0;
        uint64_t files = 0;
        r.get(mInfo.dims);
        r.get(type);
        r.get(mInfo.spacing);
        r.get(mInfo.origin);
        r.get(mName);
        uint8_t oriented = 0;
        r.get(oriented);
        mInfo.hasOrientation = oriented != 0;
        for (int c = 0; c < 3; ++c) r.get(mInfo.direction[c]);
        r.get(files);
        mInfo.type = ScalarType(type);
        for (uint64_t i = 0; i < files; ++i) {
            std::string f;
            r.get(f);
            mFiles.push_back(std::move(f));
        }
    }

    const VolumeInfo& info() const override { return mInfo; }

    void read(void* dst, int64_t count) override {
        throwIfInterrupted(mName);
        command('R', uint64_t(count));
        auto* out = static_cast<unsigned char*>(dst);
        const size_t sliceBytes = size_t(mInfo.sliceSamples()) * scalarSize(mInfo.type);
        for (int64_t s = 0; s < count; ++s) {
            uint8_t status = 0;
            uint64_t size = 0;
            const int fd = mHelper.socket();
            if (!receiveAll(fd, &status, 1) || !receiveAll(fd, &size, sizeof(size))) died("reading it");
            if (status == 0 && size == sliceBytes) {
                if (!receiveAll(fd, out + size_t(s) * sliceBytes, sliceBytes)) died("reading it");
                continue;
            }
            std::string message(size < (1u << 20) ? size_t(size) : 0, '\0');
            if (status != 1 || size >= (1u << 20) || !receiveAll(fd, message.data(), message.size()))
                died("reading it");
            throw IoError(message);
        }
    }

    // The helper's reader skips (cheaply where it can); nothing crosses the socket but a reply.
    void skip(int64_t count) override {
        if (count < 0) throw std::invalid_argument(mName + ": cannot skip a negative count of slices");
        throwIfInterrupted(mName);
        command('S', uint64_t(count));
        std::string body;
        if (reply(body, "skipping in it") != 0) throw IoError(body);
    }

    void finish() override {
        command('F', 0);
        std::string body;
        if (reply(body, "finishing it") != 0) throw IoError(body);
    }

    std::string name() const override { return mName; }
    std::vector<std::string> files() const override { return mFiles; }

private:
    void command(char c, uint64_t count) {
        const int fd = mHelper.socket();
        if (!mHelper.running() || !sendAll(fd, &c, 1) || !sendAll(fd, &count, sizeof(count)))
            died("reading it");
    }
    uint8_t reply(std::string& body, const char* doing) {
        uint8_t status = 0;
        if (!mHelper.running() || !receiveReply(mHelper.socket(), status, body)) died(doing);
        return status;
    }
    [[noreturn]] void died(const char* doing) {
        mHelper.died(mName, mLibrary, doing,
                     "the file is damaged or in a form " + mLibrary + " cannot handle");
    }

    std::string mName, mLibrary;
    HelperProcess mHelper;
    VolumeInfo mInfo;
    std::vector<std::string> mFiles;
};

}  // namespace

std::unique_ptr<SliceReader> openIsolatedReader(
    const std::string& name, const std::string& library,
    const std::function<std::unique_ptr<SliceReader>()>& open) {
    return std::make_unique<IsolatedReader>(name, library, open);
}

}  // namespace vdiso
