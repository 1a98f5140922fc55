// One ranged GET with its tries, pauses and redirects (RemoteFile::fetch), run by the session's
// transfer loop: each try is submitted, judged on the loop's thread when it ends, and then
// answers, fails, or sends the next try, at once or after a pause on the loop's timer.
#include "io/remote/remote_file.h"

#include <algorithm>
#include <chrono>
#include <cstring>

#include "core/interrupt.h"
#include "io/error.h"
#include "io/remote/http_answer.h"
#include "io/remote/remote_file_impl.h"

namespace vdiso {

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
    // A straggler: no answer `session->stragglerMs()` after the transfer began (libcurl's clock:
    // from when the loop took it, not from when it was submitted, so that a request waiting its
    // turn behind the session's bound is not judged; asked while waiting, so that a request sent
    // before the session knew its usual wait is judged too); ended, to be tried again. No
    // session: no deadline.
    const RemoteSession* session = nullptr;
    int64_t stallMs = 0;
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
        curl_off_t elapsedUs = 0;
        if (deadline > 0 && deadline < t.stallMs &&
            curlLibrary().easy_getinfo(t.curl, CURLINFO_TOTAL_TIME_T, &elapsedUs) == CURLE_OK &&
            elapsedUs > deadline * 1000) {
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

// A fetch in progress: what fetch() kept in its locals across tries, and the try in flight.
struct RemoteFile::Fetch {
    using Clock = std::chrono::steady_clock;
    uint64_t offset = 0;
    size_t n = 0;
    void* dst = nullptr;
    bool opening = false;
    bool alone = false;  // its failure for good is its own (failFetch)
    const std::atomic<bool>* cancel = nullptr;
    FetchDone done;
    std::string range, deadlineText;
    Clock::time_point deadline;
    uint64_t failuresAtStart = 0;  // a failure for good counts once, and ends the object's other transfers
    std::string url;               // where this read goes: the location, or where it was redirected
    int attempt = 0, redirects = 0;
    bool moved = true;  // every redirect so far was permanent (301, 308)
    // A read is ended as a straggler once: its next try waits up to the stall timeout. (Cut at
    // every try, a server that turned slow after the session learnt its usual wait used up the
    // read's attempts on answers that were coming.)
    bool stragglerEnded = false;
    std::string lastProblem;
    // The try in flight.
    CURL* curl = nullptr;
    curl_slist* headers = nullptr;
    Transfer t;
    char curlError[CURL_ERROR_SIZE] = {};
};

RemoteFile::Answer RemoteFile::fetch(uint64_t offset, size_t n, void* dst, bool opening,
                                     const std::atomic<bool>* cancel) const {
    DoneLatch latch;
    Answer answer;
    auto signal = latch.signal();
    fetchAsync(offset, n, dst, opening, cancel, [&answer, signal](const Answer* a, std::exception_ptr e) {
        if (a) answer = *a;
        signal(e);
    });
    latch.wait();
    return answer;
}

void RemoteFile::fetchAsync(uint64_t offset, size_t n, void* dst, bool opening, const std::atomic<bool>* cancel,
                            FetchDone done, bool alone) const {
    const RemoteOptions& options = mImpl->session->options();
    auto f = std::make_shared<Fetch>();
    f->offset = offset;
    f->n = n;
    f->dst = dst;
    f->opening = opening;
    f->alone = alone;
    f->cancel = cancel;
    f->done = std::move(done);
    f->range = std::to_string(offset) + "-" + std::to_string(offset + n - 1);
    f->deadline = Fetch::Clock::now() + std::chrono::milliseconds(std::max<int64_t>(1, options.deadlineMs));
    f->deadlineText = std::to_string(std::max<int64_t>(1, options.deadlineMs / 1000)) + " s";
    f->failuresAtStart = mImpl->failures.load();
    f->url = mImpl->where();
    sendTry(f);
}

namespace {

// A read's failure for good; unless it is `alone`, counted as the object's, which ends its other
// reads in flight (their frame is lost).
IoError failFetch(bool alone, std::atomic<uint64_t>& failures, std::mutex& failureLock, std::string& failure,
                  const std::string& name, const std::string& what) {
    if (alone) return IoError(name + ": " + what);
    std::lock_guard lock(failureLock);
    failure = name + ": " + what;
    ++failures;
    return IoError(failure);
}

}  // namespace

void RemoteFile::sendTry(const std::shared_ptr<Fetch>& fp) const {
    Fetch& f = *fp;
    Impl& d = *mImpl;
    const RemoteOptions& options = d.session->options();
    using Clock = Fetch::Clock;
    try {
        auto fail = [&](const std::string& what) { return failFetch(f.alone, d.failures, d.failureLock, d.failure, mName, what); };
        if (f.attempt >= options.attempts)
            throw fail(f.lastProblem + " (tried " + std::to_string(options.attempts) + " times)");
        throwIfInterrupted(mName);
        if (options.stop && options.stop->load()) throw IoError(mName + ": read ended: the server is stopping");
        if (f.cancel && f.cancel->load())
            throw IoError(mName + ": read of range " + f.range + " cancelled by its reader");
        if (d.failures.load() != f.failuresAtStart) {
            std::lock_guard lock(d.failureLock);
            throw IoError(d.failure);
        }
        const int64_t remainingMs =
            std::chrono::duration_cast<std::chrono::milliseconds>(f.deadline - Clock::now()).count();
        if (remainingMs <= 0)
            throw fail("no whole answer to range " + f.range + " within " + f.deadlineText + " (--remote-deadline)" +
                       (f.lastProblem.empty() ? std::string() : "; last: " + f.lastProblem));
        CURL* curl = d.session->take();
        f.curl = curl;
        f.t = Transfer{};
        Transfer& t = f.t;
        t.curl = curl;
        t.failures = &d.failures;
        t.failuresAtStart = f.failuresAtStart;
        t.stop = options.stop.get();
        t.cancel = f.cancel;
        t.dst = static_cast<unsigned char*>(f.dst);
        t.capacity = f.n;
        t.opening = f.opening;
        // Not on the open's request, nor on a read ended as a straggler once; nor beyond the stall
        // timeout, which ends a transfer anyway.
        if (!f.opening && !f.stragglerEnded) t.session = d.session.get();
        t.stallMs = options.stallTimeoutMs;
        f.headers = nullptr;
        for (const curl_slist* h = d.headers; h; h = h->next) f.headers = curlLibrary().slist_append(f.headers, h->data);
        if (!d.condition.empty()) f.headers = curlLibrary().slist_append(f.headers, d.condition.c_str());
        f.curlError[0] = 0;
        curlLibrary().easy_setopt(curl, CURLOPT_URL, f.url.c_str());
        curlLibrary().easy_setopt(curl, CURLOPT_RANGE, f.range.c_str());
        curlLibrary().easy_setopt(curl, CURLOPT_HTTPHEADER, f.headers);
        curlLibrary().easy_setopt(curl, CURLOPT_PROTOCOLS_STR, "http,https");
        // Redirects are followed here, not by libcurl: it drops Authorization on another host but
        // sends every other header, S3's session token among them, wherever it is sent.
        curlLibrary().easy_setopt(curl, CURLOPT_FOLLOWLOCATION, 0L);
        curlLibrary().easy_setopt(curl, CURLOPT_NOSIGNAL, 1L);
        curlLibrary().easy_setopt(curl, CURLOPT_HTTP_VERSION, long(CURL_HTTP_VERSION_2TLS));
        curlLibrary().easy_setopt(curl, CURLOPT_CONNECTTIMEOUT_MS, long(std::min(options.connectTimeoutMs, remainingMs)));
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
        curlLibrary().easy_setopt(curl, CURLOPT_ERRORBUFFER, f.curlError);
        // The deadline's remainder counts from here: a try waiting its turn behind the session's
        // bound waits within it (the loop sets CURLOPT_TIMEOUT_MS from it when the try starts).
        d.session->loop().submit(curl, [this, fp](CURLcode rc) { tryEnded(fp, rc); }, f.deadline);
    } catch (...) {
        if (f.curl) d.session->give(f.curl);
        f.curl = nullptr;
        curlLibrary().slist_free_all(f.headers);
        f.headers = nullptr;
        f.done(nullptr, std::current_exception());
    }
}

void RemoteFile::tryEnded(const std::shared_ptr<Fetch>& fp, CURLcode rc) const {
    Fetch& f = *fp;
    Impl& d = *mImpl;
    // Judged inside the try; what follows (the answer, the next try, the failure) outside it, so
    // that the callback is called once whatever it does.
    Answer answer;
    int64_t pauseMs = 0;
    std::exception_ptr failure;
    bool answered = false;
    try {
        answered = judgeTry(f, rc, answer, pauseMs);
        if (!answered && pauseMs > 0 && Fetch::Clock::now() + std::chrono::milliseconds(pauseMs) > f.deadline)
            throw failFetch(f.alone, d.failures, d.failureLock, d.failure, mName,
                            f.lastProblem + "; waiting " + std::to_string(pauseMs) + " ms to try again would pass the " +
                                f.deadlineText + " a read may take (--remote-deadline)");
    } catch (...) {
        failure = std::current_exception();
    }
    if (failure) return f.done(nullptr, failure);
    if (answered) return f.done(&answer, nullptr);
    if (pauseMs <= 0) return sendTry(fp);
    // The pause ends early when the read would end anyway (sendTry then says why).
    const std::atomic<bool>* stop = d.session->options().stop.get();
    d.session->loop().after(pauseMs, [this, fp] { sendTry(fp); }, [this, fp, stop] {
        return mImpl->failures.load() != fp->failuresAtStart || interruptRequested() || (stop && stop->load()) ||
               (fp->cancel && fp->cancel->load());
    });
}

bool RemoteFile::judgeTry(Fetch& f, CURLcode rc, Answer& answer, int64_t& pauseMs) const {
    Impl& d = *mImpl;
    const RemoteOptions& options = d.session->options();
    Transfer& t = f.t;
    const uint64_t offset = f.offset;
    const size_t n = f.n;
    const bool opening = f.opening;
    const std::string& range = f.range;
    CURL* curl = f.curl;
    auto fail = [&](const std::string& what) { return failFetch(f.alone, d.failures, d.failureLock, d.failure, mName, what); };
    auto stopping = [&] { return options.stop && options.stop->load(); };
    curlLibrary().easy_getinfo(curl, CURLINFO_RESPONSE_CODE, &t.status);
    curl_off_t firstByteUs = 0;
    curlLibrary().easy_getinfo(curl, CURLINFO_STARTTRANSFER_TIME_T, &firstByteUs);
    std::string redirectTo;
    if (const char* to = nullptr; curlLibrary().easy_getinfo(curl, CURLINFO_REDIRECT_URL, &to) == CURLE_OK && to)
        redirectTo = to;
    curlLibrary().slist_free_all(f.headers);
    f.headers = nullptr;
    d.session->give(curl);
    f.curl = nullptr;
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
        throw fail("sent more than the " + std::to_string(n) + " bytes of range " + range + " it announced");
    if (rc == CURLE_ABORTED_BY_CALLBACK && t.straggler) {
        ++d.session->stragglers;
        f.stragglerEnded = true;
        f.lastProblem = "no answer to range " + range + " in " + std::to_string(t.stragglerMs) + " ms, " +
                        std::to_string(RemoteSession::kStragglerFactor) + " times the usual wait (a straggler)";
        ++f.attempt;
        return false;
    }
    if (rc == CURLE_ABORTED_BY_CALLBACK) {
        throwIfInterrupted(mName);
        if (stopping()) throw IoError(mName + ": read ended: the server is stopping");
        if (f.cancel && f.cancel->load()) throw IoError(mName + ": read of range " + range + " cancelled by its reader");
        std::lock_guard lock(d.failureLock);
        throw IoError(d.failure);
    }
    if (rc != CURLE_OK) {
        const std::string what = f.curlError[0] ? f.curlError : curlLibrary().easy_strerror(rc);
        // libcurl's whole-transfer timeout (the deadline's remainder) rather than its stall one.
        if (rc == CURLE_OPERATION_TIMEDOUT && Fetch::Clock::now() + std::chrono::milliseconds(100) >= f.deadline)
            throw fail("no whole answer to range " + range + " within " + f.deadlineText +
                       " (--remote-deadline): the server sends too slowly or not at all");
        if (retriedCurlError(rc)) {
            f.lastProblem = rc == CURLE_OPERATION_TIMEDOUT
                                ? "no answer for " + std::to_string(std::max<int64_t>(1, options.stallTimeoutMs / 1000)) +
                                      " s (" + what + ")"
                                : what;
            pauseMs = int64_t(100) << std::min(f.attempt, 6);
            ++f.attempt;
            return false;
        }
        throw fail(what);
    }
    if (http_answer::isRedirect(t.status)) {
        const std::string said = "HTTP " + std::to_string(t.status);
        if (!options.followRedirects || redirectTo.empty())
            throw fail("answered " + said +
                       (redirectTo.empty() ? " without a Location" : " to " + displayLocation(redirectTo)) +
                       ", which is not followed");
        if (++f.redirects > 8)
            throw fail("redirects too often (a loop?): more than 8 redirects, the last to " +
                       displayLocation(redirectTo));
        const std::optional<std::string> from = http_answer::originOf(f.url);
        const std::optional<std::string> to = http_answer::originOf(redirectTo);
        if (!to || (to->rfind("http://", 0) != 0 && to->rfind("https://", 0) != 0))
            throw fail("was redirected (" + said + ") to " + displayLocation(redirectTo) +
                       ", which is not an http or https URL");
        // Credentials go only where they were meant for: S3 never sends a signed request
        // elsewhere on its own terms (its SDKs refuse, or sign anew for the region it names).
        if (d.credentialed && from != to)
            throw fail("was redirected (" + said + ") from " + displayLocation(f.url) + " to " +
                       displayLocation(redirectTo) + ": the request's credentials are for " + *from +
                       " only, so the redirect is not followed" +
                       (t.bucketRegion.empty() ? std::string()
                                               : " (S3 says the bucket is in region " + t.bucketRegion +
                                                     ": set AWS_REGION or --s3-endpoint for it)"));
        f.moved = f.moved && (t.status == 301 || t.status == 308);
        f.url = redirectTo;
        return false;
    }
    // Answered after permanent redirects only: the object's later reads go straight there.
    auto remember = [&] {
        if (f.redirects > 0 && f.moved) d.moveTo(f.url);
    };
    if (t.status == 200 && t.wholeObject) {  // opening, a small object sent whole
        if (t.got > n) throw fail("sent more than the " + std::to_string(n) + " bytes it may be read whole in");
        answer = Answer{t.got, t.got, t.etag, t.lastModified};
        remember();
        return true;
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
            f.lastProblem = "the body of range " + range + " ended after " + std::to_string(t.got) + " of " +
                            std::to_string(last - offset + 1) + " bytes";
            pauseMs = int64_t(100) << std::min(f.attempt, 6);
            ++f.attempt;
            return false;
        }
        if (!opening && (*r)[2] != mSize)
            throw fail("now has " + std::to_string((*r)[2]) + " bytes where it had " + std::to_string(mSize) +
                       " when opened: it was replaced while being read");
        // A server that ignores If-Match still names the version it sent.
        if (!opening && ((!d.pinnedEtag.empty() && !t.etag.empty() && t.etag != d.pinnedEtag) ||
                         (!d.pinnedLastModified.empty() && !t.lastModified.empty() &&
                          t.lastModified != d.pinnedLastModified)))
            throw fail("was replaced since it was opened: range " + range + " came as version " +
                       (t.etag.empty() ? "Last-Modified: " + t.lastModified : t.etag) + ", opened as " + mVersion);
        answer = Answer{(*r)[2], t.got, t.etag, t.lastModified};
        remember();
        return true;
    }
    const std::string said = "HTTP " + std::to_string(t.status) + http_answer::statusReason(t.status) +
                             http_answer::s3ErrorText(t.errorBody);
    if (t.status == 412)
        throw fail("was replaced while being read (version " + mVersion + " no longer matches: " + said + ")");
    if (t.status == 416 && opening) throw fail("is empty (" + said + ")");
    if (t.status >= 500 || t.status == 429) {
        f.lastProblem = said + " for range " + range;
        // The server's own wait, if it names one and it is longer than ours.
        const int64_t asked = http_answer::retryAfterMs(t.retryAfter);
        pauseMs = std::max(asked, int64_t(100) << std::min(f.attempt, 6));
        if (asked > 0) f.lastProblem += " (Retry-After: " + t.retryAfter + ")";
        ++f.attempt;
        return false;
    }
    if (t.status == 404) {
        IoError e = fail(said);
        throw RemoteNotFound(e.what());
    }
    throw fail(said + " for range " + range);
}

}  // namespace vdiso
