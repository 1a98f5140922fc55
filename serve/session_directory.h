// The server's viewers by session id, and who follows whom (follow mode, docs/protocol.md).
//
// Every session leads a group of its own when it starts. A viewer that connects with
// ?follow=ID joins the group of session ID: the group's leader sends the VIEWs, and each frame
// it makes is written into every member's output at once (the extraction runs once for all;
// each member's chunks and REFS follow what that member holds). The leader can hand over
// control to a follower; when it leaves, its first follower leads. Frame numbers run through
// the group, so a new leader's VIEWs continue them. Every change of a group is told to each of
// its members with a `role` message. Thread-safe; one lock for the whole directory (changes
// are rare: a connection, a hand-over, a VIEW's check). Lock order: the directory, then a
// session's own lock, then the frame pool's.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "serve/frame_stream.h"
#include "serve/protocol.h"

namespace vdiso::serve {

// What the directory asks of a session.
class FollowedSession {
public:
    virtual ~FollowedSession() = default;
    // The leader of a group gets a new member while it has a view: make that view's frame for
    // `output` alone (the follower's first picture).
    virtual void catchUp(std::shared_ptr<ViewerOutput> output, const ViewMessage& view) = 0;
    // This session no longer leads: its frame in flight stops at its next brick.
    virtual void stopLeading() = 0;
};

class SessionDirectory {
public:
    // Enrolls a session with its output; returns its new id (8 random hex digits). It leads a
    // group of its own.
    std::string add(FollowedSession& session, std::shared_ptr<ViewerOutput> output);
    // Session `id` leaves; its group is told, and if it led, its first follower leads.
    void remove(const std::string& id);
    // Session `id` follows `leader` (or the group `leader` is in). Throws ProtocolError naming
    // `leader` when no session has that id, or when it is `id` itself.
    void follow(const std::string& id, const std::string& leader);
    // A VIEW from session `id`, checked (it leads its group; its seq follows the group's last
    // frame) and kept as the group's view. Throws ProtocolError saying what is wrong.
    void acceptView(const std::string& id, const ViewMessage& view);
    // Session `id` gives control to follower `to` (empty: its first follower); throws
    // ProtocolError when `id` does not lead or `to` is not in its group.
    void handOver(const std::string& id, const std::string& to);
    // Where a frame of session `id` goes: its own output first, then its followers', in the
    // order they joined. Empty when `id` does not lead its group.
    std::vector<std::shared_ptr<ViewerOutput>> outputsOf(const std::string& id);

private:
    struct Group {
        std::vector<std::string> members;  // the leader first, then followers in joining order
        std::optional<ViewMessage> view;   // the leader's last
    };
    struct Entry {
        FollowedSession* session;
        std::shared_ptr<ViewerOutput> output;
        std::shared_ptr<Group> group;
    };
    // Tells every member of `group` who leads and who follows (`role` messages).
    void tellRolesLocked(const Group& group);

    std::mutex mMutex;
    std::unordered_map<std::string, Entry> mEntries;
};

}  // namespace vdiso::serve
