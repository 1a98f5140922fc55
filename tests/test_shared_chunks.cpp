// The server's shared chunks (serve/shared_chunks.h): a chunk is encoded by the first frame that
// claims it, found by the others, waited for while it is being encoded, dropped least recently
// used first within the budget, and a stopped encoder's claim does not hold its waiters.
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <thread>

#include "serve/chunk_codec.h"
#include "serve/shared_chunks.h"

namespace vdiso::serve {
namespace {

SharedChunks::Chunk chunkOf(uint32_t brick, size_t triangles) {
    TriangleMesh mesh;
    for (size_t t = 0; t < triangles; ++t) {
        const float x = float(t);
        for (const glm::vec3 p : {glm::vec3(x, 0, 0), glm::vec3(x + 1, 0, 0), glm::vec3(x, 1, 0)}) {
            mesh.indices.push_back(uint32_t(mesh.positions.size()));
            mesh.positions.push_back(p);
            mesh.normals.push_back({0, 0, 1});
        }
    }
    ChunkHeader header;
    header.flags = kChunkCacheable;
    header.frame = 7;
    header.brick = brick;
    header.iso = 0.5;
    return {std::make_shared<const std::vector<uint8_t>>(encodeChunk(header, mesh, PointSet{})), uint32_t(triangles)};
}

TEST(SharedChunks, ClaimedOnceFoundAfterwardsWithTheAskersFrame) {
    SharedChunks shared(uint64_t(1) << 20);
    SharedChunks::Chunk chunk;
    EXPECT_EQ(shared.findOrClaim(0.5, 3, chunk), SharedChunks::Found::Claimed);
    EXPECT_EQ(shared.findOrClaim(0.5, 3, chunk), SharedChunks::Found::Encoding);
    EXPECT_EQ(shared.findOrClaim(0.25, 3, chunk), SharedChunks::Found::Claimed);  // another isovalue
    shared.insert(0.5, 3, chunkOf(3, 10));
    ASSERT_EQ(shared.findOrClaim(0.5, 3, chunk), SharedChunks::Found::Held);
    EXPECT_EQ(chunk.triangles, 10u);
    const std::vector<uint8_t> message = SharedChunks::forFrame(chunk, 42);
    const DecodedChunk decoded = decodeChunk(message);
    EXPECT_EQ(decoded.header.frame, 42u);
    EXPECT_EQ(decoded.header.brick, 3u);
    EXPECT_EQ(decoded.mesh.triangleCount(), 10u);
    EXPECT_EQ(shared.counters().encoded, 1u);
    EXPECT_EQ(shared.counters().reused, 1u);
}

TEST(SharedChunks, AWaiterGetsTheChunkOrNothingWhenItsEncoderStops) {
    SharedChunks shared(uint64_t(1) << 20);
    SharedChunks::Chunk chunk;
    ASSERT_EQ(shared.findOrClaim(0.5, 1, chunk), SharedChunks::Found::Claimed);
    ASSERT_EQ(shared.findOrClaim(0.5, 1, chunk), SharedChunks::Found::Encoding);
    auto waiting = std::async(std::launch::async, [&] { return shared.wait(0.5, 1); });
    EXPECT_EQ(waiting.wait_for(std::chrono::milliseconds(50)), std::future_status::timeout);  // still encoding
    shared.insert(0.5, 1, chunkOf(1, 4));
    const std::optional<SharedChunks::Chunk> got = waiting.get();
    ASSERT_TRUE(got);
    EXPECT_EQ(got->triangles, 4u);

    ASSERT_EQ(shared.findOrClaim(0.5, 2, chunk), SharedChunks::Found::Claimed);
    auto stopped = std::async(std::launch::async, [&] { return shared.wait(0.5, 2); });
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    shared.release(0.5, 2);
    EXPECT_FALSE(stopped.get());
    EXPECT_EQ(shared.findOrClaim(0.5, 2, chunk), SharedChunks::Found::Claimed);  // free to claim again
}

TEST(SharedChunks, TheLeastRecentlyUsedGoFirstWithinTheBudget) {
    const SharedChunks::Chunk probe = chunkOf(0, 50);
    const uint64_t size = probe.message->size();
    SharedChunks shared(3 * size);  // room for three of these
    SharedChunks::Chunk chunk;
    for (uint32_t b = 0; b < 3; ++b) {
        ASSERT_EQ(shared.findOrClaim(0.5, b, chunk), SharedChunks::Found::Claimed);
        shared.insert(0.5, b, chunkOf(b, 50));
    }
    ASSERT_EQ(shared.findOrClaim(0.5, 0, chunk), SharedChunks::Found::Held);  // 0 is now the most recent
    ASSERT_EQ(shared.findOrClaim(0.5, 3, chunk), SharedChunks::Found::Claimed);
    shared.insert(0.5, 3, chunkOf(3, 50));  // evicts 1, the least recently used
    EXPECT_EQ(shared.findOrClaim(0.5, 0, chunk), SharedChunks::Found::Held);
    EXPECT_EQ(shared.findOrClaim(0.5, 2, chunk), SharedChunks::Found::Held);
    EXPECT_EQ(shared.findOrClaim(0.5, 3, chunk), SharedChunks::Found::Held);
    EXPECT_EQ(shared.findOrClaim(0.5, 1, chunk), SharedChunks::Found::Claimed);
    EXPECT_EQ(shared.counters().evicted, 1u);
    EXPECT_LE(shared.counters().bytes, 3 * size);
    // No budget: nothing is kept, every asker encodes its own.
    SharedChunks none(0);
    EXPECT_EQ(none.findOrClaim(0.5, 9, chunk), SharedChunks::Found::Claimed);
    EXPECT_EQ(none.findOrClaim(0.5, 9, chunk), SharedChunks::Found::Claimed);
    none.insert(0.5, 9, chunkOf(9, 1));
    EXPECT_EQ(none.findOrClaim(0.5, 9, chunk), SharedChunks::Found::Claimed);
}

}  // namespace
}  // namespace vdiso::serve
