// A remote store's index read by parts (io/store/lazy_index.h): parts asked for are read and
// unpacked; closing the index abandons the parts still in flight in the background instead of
// waiting for their transfers (a one-shot view would otherwise wait at exit for parts it never
// needed); the directory is taken from the header's copy without a read, and read where it lies
// when the copy is damaged.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "io/error.h"
#include "io/store/byte_source.h"
#include "io/store/index_parts.h"
#include "io/store/lazy_index.h"
#include "io/store/store_format.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

// Bytes in memory (a packed index, or a whole store), counting the reads asked of them. Reads
// asked for in the background (readCoveringAsync with a cancel flag) are held, as a transfer from
// a server that has not answered yet would be, until the flag is set: then they fail, on a
// thread of the source's own, as a remote source's transfer thread reports them.
class HeldSource final : public ByteSource {
public:
    explicit HeldSource(std::vector<unsigned char> bytes) : mBytes(std::move(bytes)) {}
    ~HeldSource() override {
        {
            std::lock_guard lock(mLock);
            mQuit = true;
        }
        if (mWatcher.joinable()) mWatcher.join();
    }
    const std::string& name() const override { return mName; }
    uint64_t size() const override { return mBytes.size(); }
    const char* method() const override { return "memory"; }
    bool readsInBackground() const override { return true; }
    void read(uint64_t offset, size_t n, void* dst, const char*, const RangeCheck&) const override {
        ++mReads;
        std::memcpy(dst, mBytes.data() + offset, n);
    }
    void readCoveringAsync(uint64_t offset, size_t n, void* dst, std::vector<ByteRange> pieces, const char* what,
                           RangeCheck intact, const std::atomic<bool>* cancel, ReadDone done,
                           bool alone) const override {
        if (!cancel) return ByteSource::readCoveringAsync(offset, n, dst, pieces, what, intact, cancel, done, alone);
        ++mHeld;
        std::lock_guard lock(mLock);
        mHeldReads.emplace_back(cancel, std::move(done));
        if (!mWatcher.joinable()) mWatcher = std::thread([this] { watch(); });
    }
    mutable std::atomic<int> mHeld{0}, mCancelled{0}, mReads{0};

private:
    void watch() const {
        for (;;) {
            std::vector<ReadDone> ended;
            {
                std::lock_guard lock(mLock);
                for (size_t k = 0; k < mHeldReads.size();)
                    if (mHeldReads[k].first->load()) {
                        ended.push_back(std::move(mHeldReads[k].second));
                        mHeldReads.erase(mHeldReads.begin() + ptrdiff_t(k));
                    } else {
                        ++k;
                    }
                if (mQuit && mHeldReads.empty()) return;
            }
            for (ReadDone& done : ended) {
                ++mCancelled;
                done(std::make_exception_ptr(IoError(mName + ": read cancelled")));
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
    }
    std::vector<unsigned char> mBytes;
    std::string mName = "memory://index";
    mutable std::mutex mLock;
    mutable std::vector<std::pair<const std::atomic<bool>*, ReadDone>> mHeldReads;
    mutable std::thread mWatcher;
    bool mQuit = false;
};

std::vector<unsigned char> rawIndex(size_t bytes) {
    std::vector<unsigned char> raw(bytes);
    for (size_t i = 0; i < bytes; ++i) raw[i] = static_cast<unsigned char>(i * 7 / 13);
    return raw;
}

TEST(LazyIndex, PartsAskedForAreReadAndClosingAbandonsTheBackground) {
    // 4 parts that zstd cannot shrink: about 1 MB stored each, a request each.
    std::vector<unsigned char> raw(3 * store_format::kIndexPartBytes + 100);
    uint64_t x = 88172645463325252ull;
    for (unsigned char& b : raw) {
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        b = static_cast<unsigned char>(x);
    }
    const std::vector<unsigned char> packed = store_format::packIndex(raw);
    HeldSource source(packed);
    {
        LazyIndex index(source, 0, packed.size(), raw.size());
        index.need(0, raw.size());  // in the foreground: read at once
        EXPECT_EQ(std::memcmp(index.raw(), raw.data(), raw.size()), 0);
        EXPECT_EQ(source.mReads.load(), 1 + 4);  // the directory, then a part a request
    }
    {
        // Parts that shrink to a few KB are read together, up to LazyIndex::kRequestBytes.
        const std::vector<unsigned char> small = rawIndex(raw.size());
        const std::vector<unsigned char> smallPacked = store_format::packIndex(small);
        HeldSource smallSource(smallPacked);
        LazyIndex index(smallSource, 0, smallPacked.size(), small.size());
        index.need(0, small.size());
        EXPECT_EQ(std::memcmp(index.raw(), small.data(), small.size()), 0);
        EXPECT_EQ(smallSource.mReads.load(), 1 + 1);  // the directory, then the parts at once
    }
    {
        LazyIndex index(source, 0, packed.size(), raw.size());
        index.readInBackground(0, 2);
        for (int k = 0; k < 5000 && source.mHeld.load() < 2; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        ASSERT_EQ(source.mHeld.load(), 2);
    }  // returns only because the held reads are cancelled
    EXPECT_EQ(source.mCancelled.load(), 2);
}

// A process forked while parts were on their way (Python's multiprocessing forks): those were the
// parent's requests, so the child asking for them gets an error saying what to do, not a wait for
// ever.
TEST(LazyIndex, PartsOnTheirWayAtAForkAreAnErrorInTheChild) {
    const std::vector<unsigned char> raw = rawIndex(3 * store_format::kIndexPartBytes + 100);  // 4 parts
    const std::vector<unsigned char> packed = store_format::packIndex(raw);
    HeldSource source(packed);
    LazyIndex index(source, 0, packed.size(), raw.size());
    index.readInBackground(0, 1);  // one request at a time: the last part, held
    for (int k = 0; k < 5000 && source.mHeld.load() < 1; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ASSERT_EQ(source.mHeld.load(), 1);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        ::alarm(10);  // a wait for ever ends the child with SIGALRM
        int code = 1;
        try {
            index.need(0, raw.size());
        } catch (const IoError& e) {
            code = std::string(e.what()).find("fork") != std::string::npos ? 0 : 2;
        }
        ::_exit(code);  // no destructors: this process has none of the parent's threads
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFEXITED(status)) << "the child was ended by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 0);
}

TEST(LazyIndex, TheHeadersCopyOfTheDirectorySparesItsRead) {
    test::ScratchDir dir;
    const std::string path = dir.file("head.vdiso");
    const test::CommandResult r = test::runVdiso("synth " + path + " --kind head --size 96 --quiet");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::vector<unsigned char> bytes = test::readFile(path);
    const StoreHeader header = store_format::decodeHeader(bytes.data(), bytes.size(), path);
    const uint64_t raw = store_format::indexBytes(uint64_t(store_format::totalBricks(header)));
    const uint64_t directoryBytes = store_format::indexDirectoryBytes(raw);
    // The writer put the index's directory, byte for byte, in the header.
    ASSERT_EQ(header.indexDirectoryCopy.size(), directoryBytes);
    EXPECT_EQ(std::memcmp(header.indexDirectoryCopy.data(), bytes.data() + header.indexOffset, directoryBytes), 0);

    HeldSource source(bytes);
    LazyIndex withCopy(source, header.indexOffset, header.indexBytes, raw, header.indexDirectoryCopy);
    EXPECT_EQ(source.mReads.load(), 0);
    withCopy.need(0, raw);
    // A damaged copy is passed over: the directory is read where it lies, and the index is the same.
    std::vector<unsigned char> damaged = header.indexDirectoryCopy;
    damaged[damaged.size() / 2] ^= 0x40;
    HeldSource again(bytes);
    LazyIndex withDamagedCopy(again, header.indexOffset, header.indexBytes, raw, damaged);
    EXPECT_EQ(again.mReads.load(), 1);
    withDamagedCopy.need(0, raw);
    EXPECT_EQ(std::memcmp(withCopy.raw(), withDamagedCopy.raw(), raw), 0);

    // A header without a copy (as written before it, or one that does not fit) decodes to none;
    // the copy's bytes are not part of the header's checksums, so older builds read it as before.
    std::fill(bytes.begin() + store_format::kDirectoryCopyAt, bytes.begin() + kStoreHeaderBytes, 0);
    EXPECT_TRUE(store_format::decodeHeader(bytes.data(), bytes.size(), path).indexDirectoryCopy.empty());
}

}  // namespace
}  // namespace vdiso
