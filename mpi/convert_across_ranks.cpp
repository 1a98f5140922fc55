#include "mpi/convert_across_ranks.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <future>
#include <limits>
#include <optional>
#include <stdexcept>

#include "core/clock.h"
#include "core/brick_levels.h"
#include "core/interrupt.h"
#include "io/atomic_output.h"
#include "io/store/brick_encoder.h"
#include "io/error.h"
#include "mpi/rank_status.h"
#include "mpi/shared_output.h"
#include "mpi/slab_partition.h"

namespace vdiso::mpi {

namespace {


// Options that do not suit the volume (--levels beyond its count, say) are wrong usage, the
// same on every rank.
int exitCodeOfOptions(const std::exception& e) { return dynamic_cast<const std::invalid_argument*>(&e) ? 2 : 1; }

// What a round carries instead of a size when its rank failed.
constexpr uint64_t kFailedMark = std::numeric_limits<uint64_t>::max();

// Thrown on the ranks that did not fail when a round shows that one did.
struct PeerFailed {};

// The collective steps of the conversion: every one is an all-gather of one number per rank,
// so a rank that failed anywhere between two of them joins the next with kFailedMark and all
// ranks leave together at that step.
class Rounds {
public:
    explicit Rounds(const Communicator& comm) : mComm(comm) {}
    // Every rank's value; throws PeerFailed when any rank failed.
    std::vector<uint64_t> exchange(uint64_t value) const {
        std::vector<uint64_t> all = mComm.allgather(value);
        for (uint64_t v : all)
            if (v == kFailedMark) throw PeerFailed{};
        return all;
    }
    void sync() const { exchange(0); }
    // Called by a rank that failed: meets the others at the step they wait in.
    void signalFailure() const { mComm.allgather(kFailedMark); }

private:
    const Communicator& mComm;
};

// A file descriptor closed when it goes.
struct Descriptor {
    int fd = -1;
    Descriptor() = default;
    Descriptor(const Descriptor&) = delete;
    Descriptor& operator=(const Descriptor&) = delete;
    ~Descriptor() {
        if (fd >= 0) ::close(fd);
    }
};

// The coarse levels' slices this rank holds (neededSlices of each level from 1 on), each level a
// slab in an unnamed file beside the output, mapped shared: the kernel writes the pages back
// under memory pressure instead of holding them. Its disk space is reserved up front, so that
// a full disk is an error here rather than a SIGBUS on a write to the mapping.
class CoarseSlabs {
public:
    CoarseSlabs(const std::string& outputPath, const std::vector<BrickLevel>& levels, size_t sampleBytes,
                int ranks, int rank) {
        uint64_t total = 0;
        mLevels.resize(levels.size());
        for (size_t l = 1; l < levels.size(); ++l) {
            Slab& s = mLevels[l];
            const Dims3& dims = levels[l].volume.dims;
            s.slices = neededSlices(levels, int(l), ranks, rank);
            s.sliceBytes = size_t(dims[0] * dims[1]) * sampleBytes;
            s.offset = total;
            total = alignToStore(total + uint64_t(s.slices.size()) * s.sliceBytes);
        }
        if (total == 0) return;
        mFile.emplace(outputPath + ".levels", true);
        if (const int e = ::posix_fallocate(mFile->fd(), 0, off_t(total)); e != 0)
            throwSystemError(outputPath, "cannot reserve " + std::to_string(total >> 20) +
                                             " MiB beside it for the coarse levels' slices",
                             e);
        void* p = ::mmap(nullptr, size_t(total), PROT_READ | PROT_WRITE, MAP_SHARED, mFile->fd(), 0);
        if (p == MAP_FAILED) throwSystemError(outputPath, "cannot map the coarse levels' slices beside it", errno);
        mBytes = static_cast<unsigned char*>(p);
        mMappedBytes = size_t(total);
    }
    ~CoarseSlabs() {
        if (mBytes) ::munmap(mBytes, mMappedBytes);
    }
    CoarseSlabs(const CoarseSlabs&) = delete;
    CoarseSlabs& operator=(const CoarseSlabs&) = delete;

    // Level l's slab (l >= 1): its slices [slices.begin, slices.end).
    SliceWindow window(int l) const {
        const Slab& s = mLevels[size_t(l)];
        return {mBytes ? mBytes + s.offset : nullptr, s.sliceBytes, std::max<int64_t>(1, s.slices.size()),
                s.slices.begin};
    }
    uint64_t bytes() const { return mMappedBytes; }

private:
    struct Slab {
        IndexRange slices;
        size_t sliceBytes = 0;
        uint64_t offset = 0;
    };
    std::vector<Slab> mLevels;
    std::optional<AtomicOutputFile> mFile;  // never committed: unnamed, gone with its descriptor
    unsigned char* mBytes = nullptr;
    size_t mMappedBytes = 0;
};

// A brick's index entry and sub-block codes as they travel to rank 0.
struct PackedBrick {
    int64_t id;
    uint64_t offset;
    uint32_t storedBytes, checksum;
    float minValue, maxValue;
    uint32_t compressed, reserved;
    SubBlockCode subBlocks[kSubBlocksPerBrick];
};
static_assert(sizeof(PackedBrick) == 40 + 2 * kSubBlocksPerBrick, "no padding travels");

// One rank's conversion: its level-0 layers streamed, then its share of every coarser level.
class RankConversion {
public:
    RankConversion(const Communicator& comm, SliceReader& source, const VolumeInfo& info,
                   const StoreWriteOptions& options, int fd, const std::string& temporary,
                   const std::string& outputPath)
        : mComm(comm),
          mRounds(comm),
          mSource(source),
          mInfo(info),
          mOptions(options),
          mRank(comm.rank()),
          mRanks(comm.size()),
          mSampleBytes(scalarSize(info.type)),
          mEncoder(info.type, options),
          mWriter(fd, temporary) {
        const BrickLayout layout(info.dims, options.brickSize);
        mLevels = brickLevels(info, options.brickSize, storeLevelCount(layout, options));
        if (!level0Layers(layout.brickCounts[2], mRanks, mRank).empty())
            mRing = std::make_unique<MappedSlices>(info.dims, mSampleBytes,
                                                   2 * int64_t(options.brickSize) + kGhostBefore + kGhostAfter,
                                                   source.name());
        mSlabs = std::make_unique<CoarseSlabs>(outputPath, mLevels, mSampleBytes, mRanks, mRank);
    }

    const std::vector<BrickLevel>& levels() const { return mLevels; }
    const Rounds& rounds() const { return mRounds; }
    RankConvertFigures& figures() { return mFigures; }
    uint64_t fileEnd() const { return mFileEnd; }
    const BrickEncoder& encoder() const { return mEncoder; }
    const std::vector<PackedBrick>& bricks() const { return mBricks; }

    // Collective (rounds). Throws PeerFailed when another rank failed, or this rank's error.
    void run() {
        streamLevel0();
        for (size_t l = 1; l < mLevels.size(); ++l) convertCoarseLevel(int(l));
        mWriter.finish();
    }

private:
    // Encodes and writes layer `bk` of `level`, its slices in `window`, a group of brick rows per
    // round; with bk < 0, takes part in the rounds of a layer with nothing of its own.
    void emitLayer(const SliceWindow& window, const BrickLevel& level, int64_t bk) {
        const BrickLayout& lay = level.layout;
        const int64_t rowBricks = lay.brickCounts[0], groupRows = brickRowsPerGroup(lay);
        for (int64_t bj = 0; bj < lay.brickCounts[1]; bj += groupRows) {
            int64_t firstId = 0, count = 0;
            uint64_t mine = 0;
            if (bk >= 0) {
                firstId = lay.brickId(0, bj, bk);
                count = std::min(groupRows, lay.brickCounts[1] - bj) * rowBricks;
                mEncoder.encode(window, lay, firstId, count, level.firstBrick == 0, false, mWriter.group());
                mine = placedBytes(mWriter.group(), count);
            }
            const std::vector<uint64_t> sizes = mRounds.exchange(mine);
            uint64_t before = 0, all = 0;
            for (int r = 0; r < mRanks; ++r) {
                if (r < mRank) before += sizes[size_t(r)];
                all += sizes[size_t(r)];
            }
            if (count > 0) {
                std::vector<EncodedBrick>& group = mWriter.group();
                const uint64_t start = mFileEnd + before;
                const uint64_t end = placeBricks(group, count, start);
                for (int64_t b = 0; b < count; ++b) {
                    const EncodedBrick& eb = group[size_t(b)];
                    PackedBrick p{};
                    p.id = level.firstBrick + firstId + b;
                    p.offset = eb.entry.offset;
                    p.storedBytes = eb.entry.storedBytes;
                    p.checksum = eb.entry.checksum;
                    p.minValue = eb.entry.minValue;
                    p.maxValue = eb.entry.maxValue;
                    p.compressed = eb.entry.compressed ? 1 : 0;
                    std::copy(std::begin(eb.subBlocks), std::end(eb.subBlocks), p.subBlocks);
                    mBricks.push_back(p);
                    mFigures.bytesWritten += eb.entry.storedBytes;
                }
                mFigures.bricksWritten += uint64_t(count);
                mWriter.write(count, start, end);
            }
            mFileEnd += all;
        }
    }

    // Level 0: this rank's run of layers, streamed from its slab of the input; its level-1
    // slices filtered as their level-0 slices arrive.
    void streamLevel0() {
        const BrickLayout& layout = mLevels[0].layout;
        const IndexRange layers = level0Layers(layout.brickCounts[2], mRanks, mRank);
        const IndexRange read = level0ReadSlices(layout, mRanks, mRank);
        const int64_t longestRun = (layout.brickCounts[2] + mRanks - 1) / mRanks;
        mFigures.firstLayer = layers.begin;
        mFigures.layers = layers.size();
        if (layers.empty()) {
            for (int64_t t = 0; t < longestRun; ++t) emitLayer({}, mLevels[0], -1);
            return;
        }
        const SliceWindow ring = mRing->window();
        const bool feeds = mLevels.size() > 1;
        const IndexRange level1 = feeds ? ownedSlices(mLevels, 1, mRanks, mRank) : IndexRange{};
        const SliceWindow slab1 = feeds ? mSlabs->window(1) : SliceWindow{};
        int64_t next = level1.begin;
        mSource.skip(read.begin);
        mFigures.slicesSkipped = uint64_t(read.begin);
        readSlices(mSource, ring, read.begin, lastSliceOfLayer(layout, layers.begin) + 1);
        for (int64_t t = 0; t < longestRun; ++t) {
            if (t >= layers.size()) {
                emitLayer({}, mLevels[0], -1);
                continue;
            }
            const int64_t bk = layers.begin + t;
            throwIfInterrupted(mSource.name());
            std::future<void> prefetch;
            if (bk + 1 < layers.end)
                prefetch = std::async(std::launch::async, readSlices, std::ref(mSource), ring,
                                      lastSliceOfLayer(layout, bk) + 1, lastSliceOfLayer(layout, bk + 1) + 1);
            emitLayer(ring, mLevels[0], bk);
            // Level-1 slices whose three level-0 slices are in the ring; the reader fills
            // other slots meanwhile.
            const int64_t last = lastSliceOfLayer(layout, bk);
            for (; next < level1.end && (2 * next + 1 <= last || last == layout.dims[2] - 1); ++next)
                downsampleSlice(mInfo.type, ring, mLevels[0].volume.dims, mLevels[1].volume.dims, next,
                                slab1.slice(next));
            if (prefetch.valid()) prefetch.get();
        }
        if (next != level1.end) throw std::logic_error("vdiso-mpi convert: level 1 was not completed");
        mFigures.bytesRead = uint64_t(read.size()) * uint64_t(mInfo.sliceSamples()) * mSampleBytes;
        // The rank that read the last slice checks that the input holds no more.
        if (read.end == layout.dims[2]) mSource.finish();
    }

    // Level l >= 1: the halo from the other ranks, this rank's layers, its next-level slices.
    void convertCoarseLevel(int l) {
        const SliceWindow slab = mSlabs->window(l);
        const IndexRange own = ownedSlices(mLevels, l, mRanks, mRank);
        const IndexRange need = neededSlices(mLevels, l, mRanks, mRank);
        std::vector<Communicator::Send> sends;
        std::vector<Communicator::Receive> receives;
        int64_t longestRun = 0;
        for (int s = 0; s < mRanks; ++s) {
            longestRun = std::max(longestRun, encodedLayers(mLevels, l, mRanks, s).size());
            if (s == mRank) continue;
            if (const IndexRange out = intersect(own, neededSlices(mLevels, l, mRanks, s)); !out.empty()) {
                sends.push_back({s, slab.slice(out.begin), uint64_t(out.size()) * slab.sliceBytes});
                mFigures.haloBytesSent += sends.back().size;
            }
            if (const IndexRange in = intersect(ownedSlices(mLevels, l, mRanks, s), need); !in.empty())
                receives.push_back({s, slab.slice(in.begin), uint64_t(in.size()) * slab.sliceBytes});
        }
        // Every rank is here and well: the point-to-point exchange has no way to tell a failure.
        mRounds.sync();
        mComm.transfer(sends, receives);

        const IndexRange layers = encodedLayers(mLevels, l, mRanks, mRank);
        for (int64_t t = 0; t < longestRun; ++t)
            emitLayer(slab, mLevels[size_t(l)], t < layers.size() ? layers.begin + t : -1);

        if (size_t(l) + 1 < mLevels.size()) {
            const IndexRange next = ownedSlices(mLevels, l + 1, mRanks, mRank);
            const SliceWindow coarse = mSlabs->window(l + 1);
            for (int64_t k = next.begin; k < next.end; ++k)
                downsampleSlice(mInfo.type, slab, mLevels[size_t(l)].volume.dims,
                                mLevels[size_t(l) + 1].volume.dims, k, coarse.slice(k));
        }
    }

    const Communicator& mComm;
    Rounds mRounds;
    SliceReader& mSource;
    VolumeInfo mInfo;
    StoreWriteOptions mOptions;
    int mRank, mRanks;
    size_t mSampleBytes;
    std::vector<BrickLevel> mLevels;
    std::unique_ptr<MappedSlices> mRing;
    std::unique_ptr<CoarseSlabs> mSlabs;
    BrickEncoder mEncoder;
    BrickGroupWriter mWriter;
    uint64_t mFileEnd = kStoreHeaderBytes;  // the header is written last, at offset 0
    std::vector<PackedBrick> mBricks;       // this rank's, for rank 0's index
    RankConvertFigures mFigures;
};

// Everything that places a volume, to the last bit: ranks must agree on it.
std::string describeVolume(const VolumeInfo& v) {
    char text[512];
    const glm::dmat3& d = v.direction;
    std::snprintf(text, sizeof text,
                  "%" PRId64 " x %" PRId64 " x %" PRId64 " %s, spacing %.17g %.17g %.17g, origin %.17g %.17g %.17g, "
                  "direction %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g (%s)",
                  v.dims[0], v.dims[1], v.dims[2], scalarTypeName(v.type), v.spacing.x, v.spacing.y, v.spacing.z,
                  v.origin.x, v.origin.y, v.origin.z, d[0][0], d[0][1], d[0][2], d[1][0], d[1][1], d[1][2], d[2][0],
                  d[2][1], d[2][2], v.hasOrientation ? "oriented" : "no orientation");
    return text;
}

// Rank 0 receives every rank's bricks; the others send theirs.
std::vector<PackedBrick> gatherBricks(const Communicator& comm, const std::vector<PackedBrick>& mine) {
    const std::vector<uint64_t> counts = comm.gather(uint64_t(mine.size()), 0);
    if (comm.rank() != 0) {
        if (!mine.empty()) comm.transfer({{0, mine.data(), mine.size() * sizeof(PackedBrick)}}, {});
        return {};
    }
    uint64_t total = 0;
    for (uint64_t c : counts) total += c;
    std::vector<PackedBrick> all(static_cast<size_t>(total));
    std::copy(mine.begin(), mine.end(), all.begin());
    std::vector<Communicator::Receive> receives;
    uint64_t at = mine.size();
    for (int r = 1; r < comm.size(); ++r) {
        if (counts[size_t(r)] > 0) receives.push_back({r, all.data() + at, counts[size_t(r)] * sizeof(PackedBrick)});
        at += counts[size_t(r)];
    }
    comm.transfer({}, receives);
    return all;
}

}  // namespace

RanksConvertResult convertAcrossRanks(const Communicator& comm, const SliceReaderOpener& open,
                                      const RanksConvertOptions& options) {
    const auto start = Clock::now();
    std::unique_ptr<SliceReader> source;
    VolumeInfo info;
    // Every rank opens the input and checks the options against it.
    runPhase(comm, [&] {
        source = open();
        info = storeVolumeFor(source->info(), options.store, source->name());
    }, exitCodeOfOptions);
    const std::string first = comm.broadcast(describeVolume(info), 0);
    runPhase(comm, [&] {
        if (describeVolume(info) != first)
            throwIoError(source->name(), "is " + describeVolume(info) + " here but " + first +
                                             " on rank 0: every rank must read the same input");
    });

    // The output, refused by rank 0 if it exists (or is an input), and this rank's descriptor.
    RankSharedOutput output(comm, options.output, options.store.overwrite,
                            comm.rank() == 0 ? source->files() : std::vector<std::string>());
    Descriptor file;
    std::unique_ptr<RankConversion> conversion;
    runPhase(comm, [&] {
        file.fd = ::open(output.temporary().c_str(), O_WRONLY | O_CLOEXEC);
        if (file.fd < 0) throwSystemError(output.temporary(), "cannot open", errno);
        conversion = std::make_unique<RankConversion>(comm, *source, info, options.store, file.fd,
                                                      output.temporary(), options.output);
    });

    // The conversion, whose every collective step tells whether a rank failed.
    {
        bool failed = false;
        std::string message;
        try {
            conversion->run();
            conversion->figures().seconds = std::chrono::duration<double>(Clock::now() - start).count();
            conversion->rounds().sync();
        } catch (const PeerFailed&) {
        } catch (const std::exception& e) {
            failed = true;
            message = e.what();
            conversion->rounds().signalFailure();
        }
        agreeAllSucceeded(comm, failed, message);
    }
    const RankConvertFigures& mine = conversion->figures();

    // The index and header, by rank 0; every rank flushes what it wrote.
    const std::vector<BrickLevel>& levels = conversion->levels();
    const std::vector<PackedBrick> bricks = gatherBricks(comm, conversion->bricks());
    std::vector<uint64_t> fine = conversion->encoder().fineHistogram();
    comm.sumInto(fine, 0);
    const uint64_t fileEnd = conversion->fileEnd();
    RanksConvertResult result;
    runPhase(comm, [&] {
        if (comm.rank() == 0) {
            const int64_t total = levels.back().firstBrick + levels.back().layout.brickCount();
            std::vector<BrickEntry> entries(static_cast<size_t>(total));
            std::vector<SubBlockCode> subBlocks(size_t(total) * kSubBlocksPerBrick);
            std::vector<bool> seen(size_t(total), false);
            for (const PackedBrick& p : bricks) {
                if (p.id < 0 || p.id >= total || seen[size_t(p.id)])
                    throw std::logic_error("vdiso-mpi convert: brick " + std::to_string(p.id) + " written twice");
                seen[size_t(p.id)] = true;
                BrickEntry& e = entries[size_t(p.id)];
                e.offset = p.offset;
                e.storedBytes = p.storedBytes;
                e.checksum = p.checksum;
                e.minValue = p.minValue;
                e.maxValue = p.maxValue;
                e.compressed = p.compressed != 0;
                std::copy(std::begin(p.subBlocks), std::end(p.subBlocks),
                          subBlocks.begin() + p.id * kSubBlocksPerBrick);
            }
            if (bricks.size() != size_t(total))
                throw std::logic_error("vdiso-mpi convert: " + std::to_string(bricks.size()) + " of " +
                                       std::to_string(total) + " bricks written");
            const StoreTail tail = finishStore(info, options.store, int(levels.size()), levels[0].layout.brickCount(),
                                               entries, subBlocks, fine, fileEnd, source->name());
            writeAllAt(file.fd, tail.index.data(), tail.index.size(), fileEnd, output.temporary());
            writeAllAt(file.fd, tail.headerBytes.data(), tail.headerBytes.size(), 0, output.temporary());
            StoreWriteSummary& s = result.summary;
            s.bricks = total;
            s.levels = int(levels.size());
            s.level0Bytes = tail.level0Bytes;
            s.coarseBytes = tail.header.storedBrickBytes - tail.level0Bytes;
            s.inputBytes = info.byteSize();
            s.fileBytes = fileEnd + tail.index.size();
        }
        if (::fsync(file.fd) != 0) throwSystemError(output.temporary(), "cannot flush", errno);
        const int fd = file.fd;
        file.fd = -1;
        if (::close(fd) != 0) throwSystemError(output.temporary(), "cannot close", errno);
    });
    output.commit();

    // Each rank's figures, on rank 0.
    const auto gathered = [&](uint64_t v) { return comm.gather(v, 0); };
    const std::vector<uint64_t> firstLayer = gathered(uint64_t(mine.firstLayer)), layers = gathered(uint64_t(mine.layers)),
                                skipped = gathered(mine.slicesSkipped), read = gathered(mine.bytesRead),
                                written = gathered(mine.bricksWritten), bytes = gathered(mine.bytesWritten),
                                halo = gathered(mine.haloBytesSent);
    const std::vector<double> seconds = comm.gather(mine.seconds, 0);
    result.ranks = comm.size();
    result.volume = info;
    result.sourceName = source->name();
    for (size_t r = 0; r < firstLayer.size(); ++r) {
        RankConvertFigures f;
        f.firstLayer = int64_t(firstLayer[r]);
        f.layers = int64_t(layers[r]);
        f.slicesSkipped = skipped[r];
        f.bytesRead = read[r];
        f.bricksWritten = written[r];
        f.bytesWritten = bytes[r];
        f.haloBytesSent = halo[r];
        f.seconds = seconds[r];
        result.perRank.push_back(f);
    }
    result.summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return result;
}

}  // namespace vdiso::mpi
