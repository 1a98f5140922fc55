#include "io/readers/zarr_keys.h"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "core/interrupt.h"
#include "io/error.h"
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
        mSession = std::make_shared<RemoteSession>(remote);
    } else {
        mName = root;
    }
}

ZarrKeys::~ZarrKeys() = default;

std::string ZarrKeys::where(const std::string& key) const {
    return mSession ? mName + "/" + key : (fs::path(mRoot) / key).string();
}

std::optional<std::vector<unsigned char>> ZarrKeys::get(const std::string& key, uint64_t maxBytes) const {
    const std::string where = this->where(key);
    auto tooLarge = [&](uint64_t size) {
        throwIoError(where, "is " + std::to_string(size) + " bytes, more than the " +
                                std::to_string(maxBytes) + " it may hold");
    };
    std::vector<unsigned char> bytes;
    if (mSession) {
        std::optional<RemoteFile> object;
        try {
            // The query (a presigned URL's signature) stays on the root, not the key.
            const size_t query = mRoot.find('?');
            const std::string url = query == std::string::npos
                                        ? mRoot + "/" + key
                                        : mRoot.substr(0, query) + "/" + key + mRoot.substr(query);
            object.emplace(mSession, url, size_t(std::min<uint64_t>(maxBytes, SIZE_MAX - 1) + 1));
        } catch (const RemoteNotFound&) {
            return std::nullopt;
        }
        if (object->size() > maxBytes) tooLarge(object->size());
        bytes.resize(size_t(object->size()));
        object->read(0, bytes.size(), bytes.data());
        return bytes;
    }
    std::error_code ec;
    const auto status = fs::status(where, ec);
    if (!fs::exists(status)) return std::nullopt;
    if (!fs::is_regular_file(status)) throwIoError(where, "is not a file");
    const uint64_t size = fs::file_size(where, ec);
    if (ec) throwIoError(where, "cannot be read: " + ec.message());
    if (size > maxBytes) tooLarge(size);
    bytes.resize(size_t(size));
    std::ifstream in(where, std::ios::binary);
    if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size)))
        throwIoError(where, "cannot be read");
    return bytes;
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
