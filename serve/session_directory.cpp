#include "serve/session_directory.h"

#include <algorithm>
#include <cstdio>
#include <random>

#include "io/json.h"

namespace vdiso::serve {

std::string SessionDirectory::add(FollowedSession& session, std::shared_ptr<ViewerOutput> output) {
    static thread_local std::mt19937_64 random(std::random_device{}());
    std::lock_guard lock(mMutex);
    std::string id;
    do {
        char text[kSessionIdChars + 1];
        std::snprintf(text, sizeof text, "%08x", unsigned(random() & 0xFFFFFFFFu));
        id = text;
    } while (mEntries.contains(id));
    auto group = std::make_shared<Group>();
    group->members.push_back(id);
    mEntries.emplace(id, Entry{&session, std::move(output), std::move(group)});
    return id;
}

void SessionDirectory::remove(const std::string& id) {
    std::lock_guard lock(mMutex);
    const auto found = mEntries.find(id);
    if (found == mEntries.end()) return;
    const std::shared_ptr<Group> group = found->second.group;
    mEntries.erase(found);
    std::erase(group->members, id);
    if (!group->members.empty()) tellRolesLocked(*group);  // a new leader, or one follower fewer
}

void SessionDirectory::follow(const std::string& id, const std::string& leader) {
    std::lock_guard lock(mMutex);
    const auto self = mEntries.find(id);
    const auto led = mEntries.find(leader);
    if (self == mEntries.end()) return;
    if (led == mEntries.end())
        throw ProtocolError("follow: no viewer has session " + jsonQuote(leader) + " (it may have closed)");
    const std::shared_ptr<Group> group = led->second.group;
    if (group == self->second.group) throw ProtocolError("follow: a viewer cannot follow itself");
    std::erase(self->second.group->members, id);
    if (!self->second.group->members.empty()) tellRolesLocked(*self->second.group);
    self->second.group = group;
    group->members.push_back(id);
    tellRolesLocked(*group);
    if (group->view) mEntries.at(group->members.front()).session->catchUp(self->second.output, *group->view);
}

void SessionDirectory::acceptView(const std::string& id, const ViewMessage& view) {
    std::lock_guard lock(mMutex);
    const auto self = mEntries.find(id);
    if (self == mEntries.end()) throw ProtocolError("VIEW: this viewer's session has closed");
    Group& group = *self->second.group;
    if (group.members.front() != id)
        throw ProtocolError("VIEW: this viewer follows session " + group.members.front() +
                            ", whose VIEWs alone are drawn (its viewer may hand over control)");
    if (group.view && view.seq <= group.view->seq)
        throw ProtocolError("VIEW: seq " + std::to_string(view.seq) + " does not follow the last one (" +
                            std::to_string(group.view->seq) + ")");
    group.view = view;
}

void SessionDirectory::handOver(const std::string& id, const std::string& to) {
    std::lock_guard lock(mMutex);
    const auto self = mEntries.find(id);
    if (self == mEntries.end()) throw ProtocolError("HANDOVER: this viewer's session has closed");
    Group& group = *self->second.group;
    if (group.members.front() != id) throw ProtocolError("HANDOVER: this viewer does not lead; it follows session " + group.members.front());
    if (group.members.size() < 2) throw ProtocolError("HANDOVER: no viewer follows this one");
    const std::string next = to.empty() ? group.members[1] : to;
    const auto at = std::find(group.members.begin() + 1, group.members.end(), next);
    if (at == group.members.end()) throw ProtocolError("HANDOVER: session " + next + " does not follow this viewer");
    group.members.erase(at);
    group.members.insert(group.members.begin(), next);
    self->second.session->stopLeading();
    tellRolesLocked(group);
}

std::vector<std::shared_ptr<ViewerOutput>> SessionDirectory::outputsOf(const std::string& id) {
    std::lock_guard lock(mMutex);
    const auto found = mEntries.find(id);
    if (found == mEntries.end() || found->second.group->members.front() != id) return {};
    std::vector<std::shared_ptr<ViewerOutput>> outputs;
    for (const std::string& m : found->second.group->members) outputs.push_back(mEntries.at(m).output);
    return outputs;
}

void SessionDirectory::tellRolesLocked(const Group& group) {
    std::string followers = "[";
    for (size_t k = 1; k < group.members.size(); ++k) followers += (k > 1 ? ", " : "") + jsonQuote(group.members[k]);
    followers += "]";
    for (const std::string& m : group.members) {
        JsonObject role;
        role.add("type", "role").add("session", m).add("leader", group.members.front()).addRaw("followers", followers);
        role.add("seq", int64_t(group.view ? group.view->seq : 0));
        // Never waits: the directory's lock is held.
        mEntries.at(m).output->outbox.push(OutMessage::control(role.str()), false);
    }
}

}  // namespace vdiso::serve
