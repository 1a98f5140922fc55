// Where a Zarr hierarchy's keys (metadata documents and chunks) are read from: a local folder,
// or a prefix over HTTP(S) or S3 (https://HOST/PATH.zarr, s3://BUCKET/PATH.zarr) whose keys
// are objects. A key is fetched whole (get, getAll) or opened for reads of its parts (open: a
// shard's index and inner chunks). Remote keys are fetched as ranged GETs of at most the bound the caller
// gives (io/remote/remote_file.h: retries, timeouts, signing), through one RemoteSession so
// their connections are reused, RemoteOptions::connections at a time; an object that does not
// exist (404) is a missing key, as a missing file is.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "io/remote/remote_options.h"

namespace vdiso {

class RemoteFile;
class RemoteSession;

class ZarrKeys {
public:
    // `root` is a folder or a URL (io/remote/remote_file.h: isRemoteLocation).
    ZarrKeys(const std::string& root, const RemoteOptions& remote);
    ~ZarrKeys();

    // The root as messages show it (a URL without its query).
    const std::string& name() const { return mName; }
    // "ROOT/KEY" as messages show it.
    std::string where(const std::string& key) const;
    bool isRemote() const { return mSession != nullptr; }

    // The key's bytes, or nullopt when there is no such key. Throws IoError naming the key when
    // it holds more than maxBytes, cannot be read, or (local) is not a file.
    std::optional<std::vector<unsigned char>> get(const std::string& key, uint64_t maxBytes) const;

    // A key opened for reads of its parts (a range request each when remote; the open is one
    // request too, which brings `headBytes` of its start).
    class Object {
    public:
        ~Object();
        Object(Object&&) noexcept;
        uint64_t size() const { return mSize; }
        // Bytes [offset, offset + n) into dst; throws IoError naming the key when they are not there.
        void read(uint64_t offset, size_t n, unsigned char* dst) const;

    private:
        friend class ZarrKeys;
        Object() = default;
        std::unique_ptr<RemoteFile> mRemote;
        int mFd = -1;
        uint64_t mSize = 0;
        std::string mWhere;
    };
    // The key opened, or nullopt when there is no such key.
    std::optional<Object> open(const std::string& key, size_t headBytes) const;

    // Runs fn(0) .. fn(n - 1): RemoteOptions::connections at a time when remote, in turn when
    // local. Throws the first error.
    void forEach(size_t n, const std::function<void(size_t)>& fn) const;

    // Every key's bytes (nullopt for a missing key), fetched RemoteOptions::connections at a
    // time when remote, read in turn when local. Throws the first error, as get does.
    using Values = std::vector<std::optional<std::vector<unsigned char>>>;
    Values getAll(const std::vector<std::string>& keys, uint64_t maxBytes) const;

    // Remote requests sent and bytes received (0 for a folder).
    uint64_t requests() const;
    uint64_t bytesFetched() const;

private:
    std::string mRoot, mName;
    std::shared_ptr<RemoteSession> mSession;
};

// "a/b" from a prefix ("" for the root) and a key.
std::string joinZarrKey(const std::string& prefix, const std::string& key);

}  // namespace vdiso
