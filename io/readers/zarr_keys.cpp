#include "io/readers/zarr_keys.h"

#include <algorithm>
#include <filesystem>
#include <utility>

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/interrupt.h"
#include "io/error.h"
#include "io/remote/curl_library.h"
#include "io/remote/remote_file.h"
#include "io/remote/remote_session.h"

namespace vdiso {

namespace fs = std::filesystem;

std::string joinZarrKey(const std::string& prefix, const std::string& key) {
    return prefix.empty() ? key : key.empty() ? prefix : prefix + "/" + key;
}

ZarrKeys::ZarrKeys(const std::string& root, const RemoteOptions& remote) : mRoot(root) {
    if (isRemoteLocation(root)) {
        while (mRoot.size() > 1 && mRoot.back() == '/') mRoot.pop_back();
        mName = displayLocation(mRoot);
        curlLibraryFor(mName);  // a failure to load libcurl names the data
        mSession = std::make_shared<RemoteSession>(remote);
    } else {
        mName = root;
    }
}

ZarrKeys::~ZarrKeys() = default;

std::string ZarrKeys::where(const std::string& key) const {
    return mSession ? mName + "/" + key : (fs::path(mRoot) / key).string();
}

// Opened with maxBytes + 1 of its head, a remote key within the bound is fetched whole in the
// open's one request.
std::optional<std::vector<unsigned char>> ZarrKeys::get(const std::string& key, uint64_t maxBytes) const {
    const std::optional<Object> object = open(key, size_t(std::min<uint64_t>(maxBytes, SIZE_MAX - 1) + 1));
    if (!object) return std::nullopt;
    if (object->size() > maxBytes)
        throwIoError(where(key), "is " + std::to_string(object->size()) + " bytes, more than the " +
                                     std::to_string(maxBytes) + " it may hold");
    std::vector<unsigned char> bytes(size_t(object->size()));
    object->read(0, bytes.size(), bytes.data());
    return bytes;
}

ZarrKeys::Object::~Object() {
    if (mFd >= 0) ::close(mFd);
}

ZarrKeys::Object::Object(Object&& o) noexcept
    : mRemote(std::move(o.mRemote)), mFd(std::exchange(o.mFd, -1)), mSize(o.mSize), mWhere(std::move(o.mWhere)) {}

void ZarrKeys::Object::read(uint64_t offset, size_t n, unsigned char* dst) const {
    if (offset > mSize || n > mSize - offset)
        throwIoError(mWhere, "has no bytes " + std::to_string(offset) + ".." + std::to_string(offset + n) + " (it has " +
                                 std::to_string(mSize) + ")");
    if (mRemote) {
        mRemote->read(offset, n, dst);
        return;
    }
    size_t done = 0;
    while (done < n) {
        const ssize_t got = ::pread(mFd, dst + done, n - done, off_t(offset + done));
        if (got < 0 && errno == EINTR) continue;
        if (got <= 0) throwIoError(mWhere, got < 0 ? std::string("cannot be read: ") + std::strerror(errno) : "ended early");
        done += size_t(got);
    }
}

std::optional<ZarrKeys::Object> ZarrKeys::open(const std::string& key, size_t headBytes) const {
    Object o;
    o.mWhere = where(key);
    if (mSession) {
        try {
            // The query (a presigned URL's signature) stays on the root, not the key.
            const size_t query = mRoot.find('?');
            const std::string url = query == std::string::npos
                                        ? mRoot + "/" + key
                                        : mRoot.substr(0, query) + "/" + key + mRoot.substr(query);
            o.mRemote = std::make_unique<RemoteFile>(mSession, url, headBytes);
        } catch (const RemoteNotFound&) {
            return std::nullopt;
        }
        o.mSize = o.mRemote->size();
        return o;
    }
    std::error_code ec;
    const auto status = fs::status(o.mWhere, ec);
    if (!fs::exists(status)) return std::nullopt;
    if (!fs::is_regular_file(status)) throwIoError(o.mWhere, "is not a file");
    o.mFd = ::open(o.mWhere.c_str(), O_RDONLY | O_CLOEXEC);
    if (o.mFd < 0) throwIoError(o.mWhere, std::string("cannot be opened: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(o.mFd, &st) != 0) throwIoError(o.mWhere, std::string("cannot be read: ") + std::strerror(errno));
    o.mSize = uint64_t(st.st_size);
    return o;
}

void ZarrKeys::forEach(size_t n, const std::function<void(size_t)>& fn) const {
    if (!mSession) {
        for (size_t i = 0; i < n; ++i) {
            throwIfInterrupted(mName);
            fn(i);
        }
        return;
    }
    mSession->forEach(n, fn);
}

ZarrKeys::Values ZarrKeys::getAll(const std::vector<std::string>& keys, uint64_t maxBytes) const {
    Values values(keys.size());
    if (!mSession) {
        for (size_t i = 0; i < keys.size(); ++i) {
            throwIfInterrupted(mName);
            values[i] = get(keys[i], maxBytes);
        }
        return values;
    }
    mSession->forEach(keys.size(), [&](size_t i) { values[i] = get(keys[i], maxBytes); });
    return values;
}

uint64_t ZarrKeys::requests() const { return mSession ? mSession->requests.load() : 0; }
uint64_t ZarrKeys::bytesFetched() const { return mSession ? mSession->bytesFetched.load() : 0; }

}  // namespace vdiso
