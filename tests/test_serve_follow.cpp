// Follow mode of vdiso serve (serve/session_directory.h, docs/protocol.md "Follow mode"): a
// viewer that connects with ?follow=ID gets session ID's frames, made once for all of them;
// one that joins late gets the leader's current picture; a follower's VIEW is refused; the
// leader hands over control, and when it leaves its first follower leads.
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include <nlohmann/json.hpp>

#include "core/view_presets.h"
#include "serve/outbox.h"
#include "tests/serve_test_util.h"

namespace vdiso::serve {
namespace {

using test::presetFor;
using test::ServerFixture;
using test::viewOf;

std::vector<std::array<float, 9>> pictureOf(const ViewerClient& client, const ClientFrame& frame) {
    TriangleMesh mesh;
    PointSet points;
    client.assemble(frame, mesh, points);
    return test::canonicalTriangles(mesh);
}

// The next `role` message (skipping others), parsed.
nlohmann::json nextRole(ViewerClient& client) {
    while (true) {
        const nlohmann::json j = nlohmann::json::parse(client.readText());
        if (j.value("type", "") == "role") return j;
    }
}

// The next `error` message's text.
std::string nextError(ViewerClient& client) {
    while (true) {
        const nlohmann::json j = nlohmann::json::parse(client.readText());
        if (j.value("type", "") == "error") return j.value("message", "");
    }
}

TEST(ServeFollow, FollowersGetTheLeadersFramesMadeOnce) {
    ServerFixture fixture;
    auto leader = fixture.client();
    const std::string id = leader->session();
    ASSERT_EQ(id.size(), kSessionIdChars);
    auto first = fixture.client("follow=" + id), second = fixture.client("follow=" + id);
    EXPECT_EQ(nextRole(*first).value("leader", ""), id);
    for (uint32_t seq = 1; seq <= 2; ++seq) {
        const uint64_t passesBefore = fixture.server->counters().framePasses;
        const ClientFrame led = leader->requestFrame(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 256, 20.0 * seq), seq));
        ASSERT_EQ(led.status, "complete");
        for (ViewerClient* follower : {first.get(), second.get()}) {
            const ClientFrame seen = follower->readFollowedFrame();
            EXPECT_EQ(seen.frame, seq);
            EXPECT_EQ(seen.status, "complete");
            EXPECT_EQ(seen.missingRefs, 0u);
            EXPECT_EQ(pictureOf(*follower, seen), pictureOf(*leader, led)) << "frame " << seq;
        }
        // One traversal for the three: a coarse pass and a final one at most.
        EXPECT_LE(fixture.server->counters().framePasses - passesBefore, 2u);
    }
    // One joining now gets the leader's picture at once, without a VIEW of its own.
    auto late = fixture.client("follow=" + id);
    const ClientFrame caughtUp = late->readFollowedFrame();
    EXPECT_EQ(caughtUp.frame, 2u);
    EXPECT_EQ(caughtUp.status, "complete");
    const ClientFrame again = leader->requestFrame(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 256, 40.0), 3));
    const ClientFrame lateSees = late->readFollowedFrame();
    EXPECT_EQ(lateSees.frame, 3u);
    EXPECT_EQ(pictureOf(*late, lateSees), pictureOf(*leader, again));
}

TEST(ServeFollow, AFollowersViewIsRefusedAndTheLeaderHandsOverControl) {
    ServerFixture fixture;
    auto leader = fixture.client();
    auto follower = fixture.client("follow=" + leader->session());
    nextRole(*leader);
    nextRole(*follower);
    ASSERT_EQ(leader->requestFrame(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 128), 5)).status, "complete");
    EXPECT_EQ(follower->readFollowedFrame().frame, 5u);

    follower->sendRaw(encodeView(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 128, 30), 6)));
    EXPECT_NE(nextError(*follower).find("follows session " + leader->session()), std::string::npos);
    // A hand-over to a session that does not follow is refused.
    leader->sendRaw(encodeHandOver({"0badc0de"}));
    EXPECT_NE(nextError(*leader).find("does not follow"), std::string::npos);

    leader->sendRaw(encodeHandOver({follower->session()}));
    const nlohmann::json toOld = nextRole(*leader), toNew = nextRole(*follower);
    EXPECT_EQ(toOld.value("leader", ""), follower->session());
    EXPECT_EQ(toNew.value("leader", ""), follower->session());
    EXPECT_EQ(toNew.value("seq", 0), 5);  // frame numbers go on from the group's last
    // The new leader's VIEWs are drawn, for both; a number below the group's last is refused.
    follower->sendRaw(encodeView(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 128, 30), 4)));
    EXPECT_NE(nextError(*follower).find("does not follow the last one (5)"), std::string::npos);
    const ClientFrame led = follower->requestFrame(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 128, 30), 7));
    ASSERT_EQ(led.status, "complete");
    const ClientFrame seen = leader->readFollowedFrame();
    EXPECT_EQ(seen.frame, 7u);
    EXPECT_EQ(pictureOf(*leader, seen), pictureOf(*follower, led));
    leader->sendRaw(encodeView(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 128), 8)));
    EXPECT_NE(nextError(*leader).find("follows session " + follower->session()), std::string::npos);
}

TEST(ServeFollow, WhenTheLeaderLeavesItsFirstFollowerLeads) {
    ServerFixture fixture;
    auto leader = fixture.client();
    auto first = fixture.client("follow=" + leader->session());
    auto second = fixture.client("follow=" + leader->session());
    ASSERT_EQ(leader->requestFrame(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 128), 1)).status, "complete");
    leader->close();
    leader.reset();
    nlohmann::json role;
    do role = nextRole(*second);
    while (role.value("leader", "") != first->session());
    const ClientFrame led = first->requestFrame(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 128, 45), 2));
    ASSERT_EQ(led.status, "complete");
    ClientFrame seen;
    do seen = second->readFollowedFrame();
    while (seen.frame != 2);
    EXPECT_EQ(pictureOf(*second, seen), pictureOf(*first, led));
}

TEST(ServeFollow, FollowingNoSessionIsToldAndTheViewerLeadsItsOwn) {
    ServerFixture fixture;
    auto viewer = fixture.client("follow=12345678");
    EXPECT_NE(nextError(*viewer).find("no viewer has session \"12345678\""), std::string::npos);
    EXPECT_EQ(viewer->requestFrame(viewOf(presetFor(fixture.storePath, ViewPreset::Normal, 128), 1)).status, "complete");
    auto self = fixture.client("follow=" + viewer->session());  // fine: another viewer follows it
    EXPECT_EQ(self->readFollowedFrame().frame, 1u);
}

// A follower that reads nothing never holds up its leader: it drops out of each frame its queue
// cannot take, and the leader's frames stay complete.
TEST(ServeFollow, AFollowerThatDoesNotReadDoesNotHoldUpTheLeader) {
    ServerFixture fixture(uint64_t(256) << 20, 1, {160, 160, 160}, 0, 30, uint64_t(256) << 20, size_t(1) << 20);
    auto leader = fixture.client();
    auto stuck = fixture.client("follow=" + leader->session());
    // Each frame at another isovalue: every chunk is new, and the follower's queue (1 MB here)
    // and its socket's buffers fill within a few frames.
    uint64_t bytes = 0;
    for (uint32_t seq = 1; seq <= 12; ++seq) {
        const Camera camera = presetFor(fixture.storePath, ViewPreset::Normal, 2048, 30.0 * seq);
        const ClientFrame f = leader->requestFrame(viewOf(camera, seq, kHeadSkinIso + 20.0 * seq));
        EXPECT_EQ(f.status, "complete") << seq;
        // A frame held up by the stuck follower would wait out the outbox's patience for room
        // (under ASan a frame alone takes longer than that: only the status is checked there).
        if (!VDISO_UNDER_ASAN) {
            EXPECT_LT(f.completeSeconds, std::chrono::duration<double>(Outbox::kPushPatience).count()) << seq;
        }
        // The chunks came with its coarse frame; the final one names them.
        for (const std::vector<uint32_t>* list : {&f.chunks, &f.refs})
            for (const uint32_t brick : *list) bytes += leader->chunkBytes(0, f.iso, brick);
    }
    EXPECT_GT(bytes, uint64_t(6) << 20) << "the follower's queue never filled";
}

}  // namespace
}  // namespace vdiso::serve
