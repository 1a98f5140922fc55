#include "io/remote/remote_file.h"

#include <algorithm>
#include <cstdlib>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

#include "core/interrupt.h"
#include "io/error.h"
#include "io/remote/curl_library.h"
#include "io/remote/disk_cache.h"
#include "io/remote/http_answer.h"
#include "io/remote/s3_location.h"

namespace vdiso {

bool isRemoteLocation(const std::string& location) {
    return location.rfind("http://", 0) == 0 || location.rfind("https://", 0) == 0 ||
           location.rfind("s3://", 0) == 0;
}

std::string displayLocation(const std::string& location) {
    std::string shown = location.substr(0, location.find_first_of("?#"));
    const size_t scheme = shown.find("://");
    if (scheme != std::string::npos) {
        const size_t hostEnd = shown.find('/', scheme + 3);
        const size_t at = shown.rfind('@', hostEnd);
        if (at != std::string::npos && at > scheme) shown.erase(scheme + 3, at - scheme - 2);
    }
    return shown;
}

namespace {

// A session for reading `location`, libcurl loaded first so that a failure to load it names the
// location.
std::shared_ptr<RemoteSession> sessionFor(const std::string& location, const RemoteOptions& options) {
    curlLibraryFor(displayLocation(location));
    return std::make_shared<RemoteSession>(options);
}

}  // namespace

namespace {

// What one transfer received. Headers are those of the last response (redirects reset them).
struct Transfer {
    CURL* curl = nullptr;
    const std::atomic<uint64_t>* failures = nullptr;  // the object's permanent failures so far
    const std::atomic<bool>* stop = nullptr;          // RemoteOptions::stop
    const std::atomic<bool>* cancel = nullptr;        // the read's own (RemoteFile::read)
    uint64_t failuresAtStart = 0;
    unsigned char* dst = nullptr;
    size_t capacity = 0;
    size_t got = 0;
    bool overflow = false;
    // Opening: a 200 (the whole object where a range was asked) is taken when it fits.
    bool opening = false, wholeObject = false;
    long status = 0;
    std::string contentRange, etag, lastModified, contentEncoding, retryAfter, bucketRegion, errorBody;
    size_t headerBytes = 0;  // the response's headers so far
    bool hugeHeader = false;
    // A straggler: no answer `session->stragglerMs()` after `start` (asked while waiting, so that
    // a request sent before the session knew its usual wait is judged too); ended, to be tried
    // again. No session: no deadline.
    const RemoteSession* session = nullptr;
    int64_t stallMs = 0;
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    int64_t stragglerMs = 0;  // the deadline it was ended at
    bool answered = false, straggler = false;
};

// A response's headers are refused past this: no answer of an object store comes near it.
constexpr size_t kMaxHeaderBytes = 64 * 1024;

size_t onHeader(char* data, size_t size, size_t count, void* user) {
    auto& t = *static_cast<Transfer*>(user);
    const std::string_view line(data, size * count);
    t.answered = true;
    if (line.rfind("HTTP/", 0) == 0) {
        t.contentRange.clear();
        t.etag.clear();
        t.lastModified.clear();
        t.contentEncoding.clear();
        t.retryAfter.clear();
        t.bucketRegion.clear();
        t.headerBytes = line.size();
        return line.size();
    }
    t.headerBytes += line.size();
    if (t.headerBytes > kMaxHeaderBytes) {
        t.hugeHeader = true;
        return 0;  // ends the transfer
    }
    const size_t colon = line.find(':');
    if (colon == std::string_view::npos) return line.size();
    std::string name(line.substr(0, colon));
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    std::string_view value = line.substr(colon + 1);
    while (!value.empty() && (value.front() == ' ' || value.front() == '\t')) value.remove_prefix(1);
    while (!value.empty() && (value.back() == '\r' || value.back() == '\n' || value.back() == ' '))
        value.remove_suffix(1);
    if (name == "content-range") t.contentRange = value;
    else if (name == "etag") t.etag = value;
    else if (name == "last-modified") t.lastModified = value;
    else if (name == "content-encoding") t.contentEncoding = value;
    else if (name == "retry-after") t.retryAfter = value;
    else if (name == "x-amz-bucket-region") t.bucketRegion = value;
    return line.size();
}

// Ends a transfer on Ctrl-C, when its owner stops (RemoteOptions::stop), and when another read
// of the object failed for good meanwhile:
// the frame that wanted both is lost, so its other requests stop instead of running their tries.
// Ends a straggler too (libcurl calls this about once a second while nothing arrives).
int onProgress(void* user, curl_off_t, curl_off_t, curl_off_t, curl_off_t) {
    auto& t = *static_cast<Transfer*>(user);
    if (t.session && !t.answered) {
        const int64_t deadline = t.session->stragglerMs();
        if (deadline > 0 && deadline < t.stallMs &&
            std::chrono::steady_clock::now() - t.start > std::chrono::milliseconds(deadline)) {
            t.stragglerMs = deadline;
            t.straggler = true;
            return 1;
        }
    }
    return interruptRequested() || t.failures->load() != t.failuresAtStart || (t.stop && t.stop->load()) ||
           (t.cancel && t.cancel->load());
}

size_t onBody(char* data, size_t size, size_t count, void* user) {
    auto& t = *static_cast<Transfer*>(user);
    const size_t n = size * count;
    curlLibrary().easy_getinfo(t.curl, CURLINFO_RESPONSE_CODE, &t.status);
    if (t.status == 200 && t.opening) t.wholeObject = true;  // ranges ignored: the whole object
    if (t.status != 206 && !t.wholeObject) {
        // An error's body says why (S3's XML); a whole object where a range was asked is refused
        // by the caller from the status.
        if (t.errorBody.size() < 4096) t.errorBody.append(data, std::min(n, 4096 - t.errorBody.size()));
        return t.status == 200 ? 0 : n;
    }
    if (n > t.capacity - t.got) {
        t.overflow = true;
        return 0;
    }
    std::memcpy(t.dst + t.got, data, n);
    t.got += n;
    return n;
}

bool retriedCurlError(CURLcode rc) {
    switch (rc) {
        case CURLE_COULDNT_CONNECT:
        case CURLE_OPERATION_TIMEDOUT:
        case CURLE_RECV_ERROR:
        case CURLE_SEND_ERROR:
        case CURLE_PARTIAL_FILE:
        case CURLE_GOT_NOTHING:
        case CURLE_HTTP2:
        case CURLE_HTTP2_STREAM: return true;
        default: return false;
    }
}

}  // namespace

struct RemoteFile::Impl {
    std::shared_ptr<RemoteSession> session;
    std::string url;  // what is requested: the location, or an s3:// location's http(s) URL
    std::optional<S3Location> s3;
    std::string sigv4, userPassword;
    curl_slist* headers = nullptr;  // fixed headers: S3's payload hash and session token
    std::string condition;          // "If-Match: ..." or "If-Unmodified-Since: ...", once pinned
    std::string pinnedEtag, pinnedLastModified;  // what every answer must still say
    bool credentialed = false;      // signed, or a URL with userinfo: redirects stay at its origin
    std::atomic<uint64_t> failures{0};  // reads that failed for good
    std::mutex failureLock;
    std::string failure;  // the last one's message, which the reads it ended repeat

    ~Impl() { curlLibrary().slist_free_all(headers); }
};

RemoteFile::RemoteFile(const std::string& location, const RemoteOptions& options, size_t headBytes)
    : RemoteFile(sessionFor(location, options), location, headBytes) {}

RemoteFile::RemoteFile(std::shared_ptr<RemoteSession> session, const std::string& location,
                       size_t headBytes)
    : mImpl(std::make_unique<Impl>()), mName(displayLocation(location)) {
    Impl& d = *mImpl;
    d.session = std::move(session);
    if (location.rfind("s3://", 0) == 0) {
        d.s3 = d.session->s3Location(location);
        d.url = d.s3->url;
        mScheme = "s3";
        if (!d.s3->accessKey.empty()) {
            d.sigv4 = "aws:amz:" + d.s3->region + ":s3";
            d.userPassword = d.s3->accessKey + ":" + d.s3->secretKey;
            // S3 wants the payload's hash in a header of its own; a GET has none to sign.
            d.headers = curlLibrary().slist_append(d.headers, "x-amz-content-sha256: UNSIGNED-PAYLOAD");
            if (!d.s3->sessionToken.empty())
                d.headers = curlLibrary().slist_append(d.headers, ("x-amz-security-token: " + d.s3->sessionToken).c_str());
        }
    } else {
        d.url = location;
        mScheme = location.rfind("https://", 0) == 0 ? "https" : "http";
    }
    bool hasUser = false;
    http_answer::originOf(d.url, &hasUser);
    d.credentialed = !d.sigv4.empty() || hasUser;

    // The head: its Content-Range gives the size, its ETag the version every later read pins.
    mHead.resize(std::max<size_t>(headBytes, 1));
    const Answer head = fetch(0, mHead.size(), mHead.data(), true);
    mSize = head.total;
    mHead.resize(head.bytes);
    if (head.etag.size() > 2 && head.etag.rfind("W/", 0) != 0) {
        mVersion = head.etag;
        d.condition = "If-Match: " + head.etag;
        d.pinnedEtag = head.etag;
    } else if (!head.lastModified.empty()) {
        mVersion = "Last-Modified: " + head.lastModified;
        d.condition = "If-Unmodified-Since: " + head.lastModified;
        d.pinnedLastModified = head.lastModified;
    }
    const RemoteOptions& options = d.session->options();
    if (!options.diskCacheDir.empty()) {
        if (mVersion.empty())
            throwIoError(mName, "is served without an ETag or Last-Modified: with no version to "
                                "key them by, its ranges cannot be kept in a disk cache");
        mDiskCache = std::make_unique<RangeDiskCache>(options.diskCacheDir, displayLocation(d.url), mVersion,
                                                      options.diskCacheBytes);
    }
}

RemoteFile::~RemoteFile() = default;

uint64_t RemoteFile::requests() const { return mImpl->session->requests.load(); }
uint64_t RemoteFile::bytesFetched() const { return mImpl->session->bytesFetched.load(); }
uint64_t RemoteFile::stragglers() const { return mImpl->session->stragglers.load(); }
uint64_t RemoteFile::diskCacheHits() const { return mDiskCache ? mDiskCache->hits() : 0; }
uint64_t RemoteFile::diskCacheBytes() const { return mDiskCache ? mDiskCache->hitBytes() : 0; }

void RemoteFile::read(uint64_t offset, size_t n, void* dst, const RangeCheck& intact,
                      const std::atomic<bool>* cancel) const {
    if (n == 0) return;
    if (offset > mSize || n > mSize - offset)
        throwIoError(mName, "has " + std::to_string(mSize) + " bytes: no range " + std::to_string(offset) +
                                "-" + std::to_string(offset + n - 1));
    if (offset + n <= mHead.size()) {
        std::memcpy(dst, mHead.data() + offset, n);
        if (intact) intact(0);  // its last call is on what dst holds (RangeCheck)
        return;
    }
    if (mDiskCache && mDiskCache->read(offset, n, dst)) {
        if (!intact || intact(0)) return;
        mDiskCache->drop(offset, n);  // kept damaged (by an older vdiso): fetched anew
    }
    fetch(offset, n, dst, false, cancel);
    if (mDiskCache && (!intact || intact(0))) mDiskCache->write(offset, n, dst);
}

RemoteFile::Answer RemoteFile::fetch(uint64_t offset, size_t n, void* dst, bool opening,
                                     const std::atomic<bool>* cancel) const {
    Impl& d = *mImpl;
    const RemoteOptions& options = d.session->options();
    const std::string range = std::to_string(offset) + "-" + std::to_string(offset + n - 1);
    using Clock = std::chrono::steady_clock;
    const Clock::time_point deadline =
        Clock::now() + std::chrono::milliseconds(std::max<int64_t>(1, options.deadlineMs));
    const std::string deadlineText = std::to_string(std::max<int64_t>(1, options.deadlineMs / 1000)) + " s";
    // A failure for good counts once, and ends the object's other transfers (onProgress).
    const uint64_t failuresAtStart = d.failures.load();
    auto fail = [&](const std::string& what) {
        std::lock_guard lock(d.failureLock);
        d.failure = mName + ": " + what;
        ++d.failures;
        return IoError(d.failure);
    };
    auto abandoned = [&] {
        std::lock_guard lock(d.failureLock);
        return IoError(d.failure);
    };
    auto stopping = [&] { return options.stop && options.stop->load(); };
    auto stopped = [&] { return IoError(mName + ": read ended: the server is stopping"); };
    auto cancelled = [&] { return cancel && cancel->load(); };
    auto cancelledError = [&] { return IoError(mName + ": read of range " + range + " cancelled by its reader"); };
    std::string url = d.url;  // where this read goes: the location, or where it was redirected
    int redirects = 0;
    std::string lastProblem;
    int64_t pauseMs = 0;  // before the next try
    for (int attempt = 0; attempt < options.attempts;) {
        if (pauseMs > 0) {
            if (Clock::now() + std::chrono::milliseconds(pauseMs) > deadline)
                throw fail(lastProblem + "; waiting " + std::to_string(pauseMs) + " ms to try again would pass the " +
                           deadlineText + " a read may take (--remote-deadline)");
            const auto until = Clock::now() + std::chrono::milliseconds(pauseMs);
            while (Clock::now() < until && d.failures.load() == failuresAtStart && !interruptRequested() && !stopping() &&
                   !cancelled())
                std::this_thread::sleep_for(std::chrono::milliseconds(10));
            pauseMs = 0;
        }
        throwIfInterrupted(mName);
        if (stopping()) throw stopped();
        if (cancelled()) throw cancelledError();
        if (d.failures.load() != failuresAtStart)
            throw abandoned();
        const int64_t remainingMs =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
        if (remainingMs <= 0)
            throw fail("no whole answer to range " + range + " within " + deadlineText +
                       " (--remote-deadline)" + (lastProblem.empty() ? std::string() : "; last: " + lastProblem));
        CURL* curl = d.session->take();
        Transfer t;
        t.curl = curl;
        t.failures = &d.failures;
        t.failuresAtStart = failuresAtStart;
        t.stop = options.stop.get();
        t.cancel = cancel;
        t.dst = static_cast<unsigned char*>(dst);
        t.capacity = n;
        t.opening = opening;
        // Not on the open's request; nor beyond the stall timeout, which ends a transfer anyway.
        if (!opening) t.session = d.session.get();
        t.stallMs = options.stallTimeoutMs;
        curl_slist* headers = nullptr;
        for (const curl_slist* h = d.headers; h; h = h->next) headers = curlLibrary().slist_append(headers, h->data);
        if (!d.condition.empty()) headers = curlLibrary().slist_append(headers, d.condition.c_str());
        curlLibrary().easy_setopt(curl, CURLOPT_URL, url.c_str());
        curlLibrary().easy_setopt(curl, CURLOPT_RANGE, range.c_str());
        curlLibrary().easy_setopt(curl, CURLOPT_HTTPHEADER, headers);
        curlLibrary().easy_setopt(curl, CURLOPT_PROTOCOLS_STR, "http,https");
        // Redirects are followed here, not by libcurl: it drops Authorization on another host but
        // sends every other header, S3's session token among them, wherever it is sent.
        curlLibrary().easy_setopt(curl, CURLOPT_FOLLOWLOCATION, 0L);
        curlLibrary().easy_setopt(curl, CURLOPT_NOSIGNAL, 1L);
        curlLibrary().easy_setopt(curl, CURLOPT_HTTP_VERSION, long(CURL_HTTP_VERSION_2TLS));
        curlLibrary().easy_setopt(curl, CURLOPT_CONNECTTIMEOUT_MS, long(std::min(options.connectTimeoutMs, remainingMs)));
        curlLibrary().easy_setopt(curl, CURLOPT_TIMEOUT_MS, long(remainingMs));
        curlLibrary().easy_setopt(curl, CURLOPT_LOW_SPEED_LIMIT, 1L);
        curlLibrary().easy_setopt(curl, CURLOPT_LOW_SPEED_TIME, long(std::max<int64_t>(1, options.stallTimeoutMs / 1000)));
        curlLibrary().easy_setopt(curl, CURLOPT_HEADERFUNCTION, onHeader);
        curlLibrary().easy_setopt(curl, CURLOPT_HEADERDATA, &t);
        curlLibrary().easy_setopt(curl, CURLOPT_WRITEFUNCTION, onBody);
        curlLibrary().easy_setopt(curl, CURLOPT_WRITEDATA, &t);
        curlLibrary().easy_setopt(curl, CURLOPT_NOPROGRESS, 0L);
        curlLibrary().easy_setopt(curl, CURLOPT_XFERINFOFUNCTION, onProgress);
        curlLibrary().easy_setopt(curl, CURLOPT_XFERINFODATA, &t);
        curlLibrary().easy_setopt(curl, CURLOPT_USERAGENT, "vdiso");
        if (!options.caFile.empty()) curlLibrary().easy_setopt(curl, CURLOPT_CAINFO, options.caFile.c_str());
        if (!d.sigv4.empty()) {
            curlLibrary().easy_setopt(curl, CURLOPT_AWS_SIGV4, d.sigv4.c_str());
            curlLibrary().easy_setopt(curl, CURLOPT_USERPWD, d.userPassword.c_str());
        }
        char curlError[CURL_ERROR_SIZE] = {};
        curlLibrary().easy_setopt(curl, CURLOPT_ERRORBUFFER, curlError);
        const CURLcode rc = d.session->perform(curl);
        curlLibrary().easy_getinfo(curl, CURLINFO_RESPONSE_CODE, &t.status);
        curl_off_t firstByteUs = 0;
        curlLibrary().easy_getinfo(curl, CURLINFO_STARTTRANSFER_TIME_T, &firstByteUs);
        std::string redirectTo;
        if (const char* to = nullptr; curlLibrary().easy_getinfo(curl, CURLINFO_REDIRECT_URL, &to) == CURLE_OK && to)
            redirectTo = to;
        curlLibrary().slist_free_all(headers);
        d.session->give(curl);
        ++d.session->requests;
        d.session->bytesFetched += t.got;

        // libcurl refuses a header line longer than it holds (100 KiB) as "out of memory".
        if (t.hugeHeader || (rc == CURLE_OUT_OF_MEMORY && t.got == 0))
            throw fail("answered with more than " + std::to_string(kMaxHeaderBytes / 1024) +
                       " KiB of headers: refused (the server is broken or hostile)");
        if (!t.contentEncoding.empty() && t.contentEncoding != "identity")
            throw fail("answered range " + range + " with Content-Encoding '" + t.contentEncoding +
                       "', which was not asked for: a range must be the object's own bytes");
        if (t.status == 200 && (!t.wholeObject || t.overflow))
            throw fail(std::string("is served without byte ranges (HTTP 200 to a Range request)") +
                       (opening ? " and is larger than the " + std::to_string(n) + " bytes it may be read whole in"
                                : std::string()) +
                       ": vdiso reads remote stores by ranges, so the server must honour them");
        if (t.overflow)
            throw fail("sent more than the " + std::to_string(n) + " bytes of range " + range +
                                    " it announced");
        if (rc == CURLE_ABORTED_BY_CALLBACK && t.straggler) {
            ++d.session->stragglers;
            lastProblem = "no answer to range " + range + " in " + std::to_string(t.stragglerMs) +
                          " ms, " + std::to_string(RemoteSession::kStragglerFactor) +
                          " times the usual wait (a straggler)";
            ++attempt;
            continue;
        }
        if (rc == CURLE_ABORTED_BY_CALLBACK) {
            throwIfInterrupted(mName);
            if (stopping()) throw stopped();
            if (cancelled()) throw cancelledError();
            throw abandoned();
        }
        if (rc != CURLE_OK) {
            const std::string what = curlError[0] ? curlError : curlLibrary().easy_strerror(rc);
            // libcurl's whole-transfer timeout (the deadline's remainder) rather than its stall one.
            if (rc == CURLE_OPERATION_TIMEDOUT && Clock::now() + std::chrono::milliseconds(100) >= deadline)
                throw fail("no whole answer to range " + range + " within " + deadlineText +
                           " (--remote-deadline): the server sends too slowly or not at all");
            if (retriedCurlError(rc)) {
                lastProblem = rc == CURLE_OPERATION_TIMEDOUT
                                  ? "no answer for " + std::to_string(std::max<int64_t>(1, options.stallTimeoutMs / 1000)) +
                                        " s (" + what + ")"
                                  : what;
                pauseMs = int64_t(100) << std::min(attempt, 6);
                ++attempt;
                continue;
            }
            throw fail(what);
        }
        if (http_answer::isRedirect(t.status)) {
            const std::string said = "HTTP " + std::to_string(t.status);
            if (!options.followRedirects || redirectTo.empty())
                throw fail("answered " + said +
                           (redirectTo.empty() ? " without a Location" : " to " + displayLocation(redirectTo)) +
                           ", which is not followed");
            if (++redirects > 8)
                throw fail("redirects too often (a loop?): more than 8 redirects, the last to " +
                           displayLocation(redirectTo));
            const std::optional<std::string> from = http_answer::originOf(url);
            const std::optional<std::string> to = http_answer::originOf(redirectTo);
            if (!to || (to->rfind("http://", 0) != 0 && to->rfind("https://", 0) != 0))
                throw fail("was redirected (" + said + ") to " + displayLocation(redirectTo) +
                           ", which is not an http or https URL");
            // Credentials go only where they were meant for: S3 never sends a signed request
            // elsewhere on its own terms (its SDKs refuse, or sign anew for the region it names).
            if (d.credentialed && from != to)
                throw fail("was redirected (" + said + ") from " + displayLocation(url) + " to " +
                           displayLocation(redirectTo) + ": the request's credentials are for " + *from +
                           " only, so the redirect is not followed" +
                           (t.bucketRegion.empty() ? std::string()
                                                   : " (S3 says the bucket is in region " + t.bucketRegion +
                                                         ": set AWS_REGION or --s3-endpoint for it)"));
            url = redirectTo;
            continue;
        }
        if (t.status == 200 && t.wholeObject) {  // opening, a small object sent whole
            if (t.got > n)
                throw fail("sent more than the " + std::to_string(n) + " bytes it may be read whole in");
            return Answer{t.got, t.got, t.etag, t.lastModified};
        }
        if (t.status == 206) {
            d.session->noteFirstByteMs(double(firstByteUs) / 1000.0);
            const auto r = http_answer::parseContentRange(t.contentRange);
            // Opening asks for the head, which may be longer than a small object.
            const uint64_t last = opening && r ? std::min<uint64_t>(offset + n, (*r)[2]) - 1 : offset + n - 1;
            if (!r || (*r)[0] != offset || (*r)[1] != last)
                throw fail("answered range " + range + " with Content-Range '" + t.contentRange +
                                        "': the server is broken or the object changed");
            if (t.got != last - offset + 1) {
                lastProblem = "the body of range " + range + " ended after " + std::to_string(t.got) +
                              " of " + std::to_string(last - offset + 1) + " bytes";
                pauseMs = int64_t(100) << std::min(attempt, 6);
                ++attempt;
                continue;
            }
            if (!opening && (*r)[2] != mSize)
                throw fail("now has " + std::to_string((*r)[2]) + " bytes where it had " +
                                        std::to_string(mSize) + " when opened: it was replaced while being read");
            // A server that ignores If-Match still names the version it sent.
            if (!opening && ((!d.pinnedEtag.empty() && !t.etag.empty() && t.etag != d.pinnedEtag) ||
                             (!d.pinnedLastModified.empty() && !t.lastModified.empty() &&
                              t.lastModified != d.pinnedLastModified)))
                throw fail("was replaced since it was opened: range " + range + " came as version " +
                           (t.etag.empty() ? "Last-Modified: " + t.lastModified : t.etag) + ", opened as " + mVersion);
            return Answer{(*r)[2], t.got, t.etag, t.lastModified};
        }
        const std::string said = "HTTP " + std::to_string(t.status) + http_answer::statusReason(t.status) +
                                 http_answer::s3ErrorText(t.errorBody);
        if (t.status == 412)
            throw fail("was replaced while being read (version " + mVersion + " no longer matches: " +
                                    said + ")");
        if (t.status == 416 && opening) throw fail("is empty (" + said + ")");
        if (t.status >= 500 || t.status == 429) {
            lastProblem = said;
            // The server's own wait, if it names one and it is longer than ours.
            const int64_t asked = http_answer::retryAfterMs(t.retryAfter);
            pauseMs = std::max(asked, int64_t(100) << std::min(attempt, 6));
            if (asked > 0) lastProblem += " (Retry-After: " + t.retryAfter + ")";
            ++attempt;
            continue;
        }
        if (t.status == 404) {
            IoError e = fail(said);
            throw RemoteNotFound(e.what());
        }
        throw fail(said + (t.status == 416 ? " for range " + range : std::string()));
    }
    throw fail(lastProblem + " (tried " + std::to_string(options.attempts) + " times)");
}

void RemoteFile::readCovering(uint64_t offset, size_t n, void* dst, std::span<const ByteRange> pieces,
                              const RangeCheck& intact) const {
    auto intactPiece = [&](size_t k) { return !intact || intact(k); };
    // The range as one piece, intact when each of its pieces is.
    const RangeCheck allIntact = intact ? RangeCheck([&](size_t) {
        for (size_t k = 0; k < pieces.size(); ++k)
            if (!intact(k)) return false;
        return true;
    }) : RangeCheck();
    if (!mDiskCache || pieces.size() < 2) return read(offset, n, dst, allIntact);
    bool held = true;
    for (size_t k = 0; k < pieces.size() && held; ++k) {
        held = mDiskCache->read(pieces[k].offset, pieces[k].bytes, pieces[k].dst);
        if (held && !intactPiece(k)) {
            mDiskCache->drop(pieces[k].offset, pieces[k].bytes);
            held = false;
        }
    }
    if (held) return;
    if (offset > mSize || n > mSize - offset || offset < mHead.size()) return read(offset, n, dst, allIntact);
    fetch(offset, n, dst, false);
    for (size_t k = 0; k < pieces.size(); ++k)
        if (intactPiece(k)) mDiskCache->write(pieces[k].offset, pieces[k].bytes, pieces[k].dst);
}

void RemoteFile::readMany(std::span<const ByteRange> ranges, const RangeCheck& intact,
                          const std::atomic<bool>* cancel) const {
    mImpl->session->forEach(ranges.size(), [&](size_t i) {
        read(ranges[i].offset, ranges[i].bytes, ranges[i].dst,
             intact ? RangeCheck([&](size_t) { return intact(i); }) : RangeCheck(), cancel);
    });
}

}  // namespace vdiso
