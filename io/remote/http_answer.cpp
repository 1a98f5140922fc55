#include "io/remote/http_answer.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <ctime>
#include <new>

#include "io/remote/curl_library.h"

namespace vdiso::http_answer {

std::string s3ErrorText(const std::string& body) {
    auto element = [&](const char* name) -> std::string {
        const std::string open = std::string("<") + name + ">", close = std::string("</") + name + ">";
        const size_t a = body.find(open);
        if (a == std::string::npos) return {};
        const size_t b = body.find(close, a);
        return b == std::string::npos ? std::string() : body.substr(a + open.size(), b - a - open.size());
    };
    const std::string code = element("Code"), message = element("Message");
    if (code.empty()) return {};
    return ": " + code + (message.empty() ? std::string() : " (" + message + ")");
}

std::optional<std::array<uint64_t, 3>> parseContentRange(const std::string& text) {
    // The unit in any case (RFC 9110), then three unsigned decimals and nothing else: sscanf's
    // %lu took "-1" as 2^64 - 1 (an object's size at the open).
    const char* p = text.data();
    const char* end = text.data() + text.size();
    while (end > p && std::isspace(static_cast<unsigned char>(end[-1]))) --end;
    constexpr char kUnit[] = "bytes ";
    for (const char* u = kUnit; *u; ++u, ++p)
        if (p == end || std::tolower(static_cast<unsigned char>(*p)) != *u) return std::nullopt;
    std::array<uint64_t, 3> v{};
    constexpr char kAfter[2] = {'-', '/'};
    for (size_t k = 0; k < 3; ++k) {
        if (p == end || !std::isdigit(static_cast<unsigned char>(*p))) return std::nullopt;
        const auto [next, error] = std::from_chars(p, end, v[k]);
        if (error != std::errc()) return std::nullopt;
        p = next;
        if (k < 2) {
            if (p == end || *p != kAfter[k]) return std::nullopt;
            ++p;
        }
    }
    if (p != end || v[1] < v[0] || v[1] >= v[2]) return std::nullopt;
    return v;
}

const char* statusReason(long status) {
    switch (status) {
        case 400: return " (Bad Request)";
        case 401: return " (Unauthorized)";
        case 403: return " (Forbidden)";
        case 404: return " (Not Found)";
        case 405: return " (Method Not Allowed)";
        case 412: return " (Precondition Failed)";
        case 416: return " (Range Not Satisfiable)";
        case 429: return " (Too Many Requests)";
        case 500: return " (Internal Server Error)";
        case 502: return " (Bad Gateway)";
        case 503: return " (Service Unavailable)";
        case 504: return " (Gateway Timeout)";
    }
    return "";
}

std::optional<std::string> originOf(const std::string& url, bool* hasUser) {
    CURLU* u = curlLibrary().url();
    if (!u) throw std::bad_alloc();
    std::optional<std::string> origin;
    if (curlLibrary().url_set(u, CURLUPART_URL, url.c_str(), 0) == CURLUE_OK) {
        char *scheme = nullptr, *host = nullptr, *port = nullptr, *user = nullptr;
        if (curlLibrary().url_get(u, CURLUPART_SCHEME, &scheme, 0) == CURLUE_OK &&
            curlLibrary().url_get(u, CURLUPART_HOST, &host, 0) == CURLUE_OK &&
            curlLibrary().url_get(u, CURLUPART_PORT, &port, CURLU_DEFAULT_PORT) == CURLUE_OK) {
            std::string text = std::string(scheme) + "://" + host + ":" + port;
            std::transform(text.begin(), text.end(), text.begin(),
                           [](unsigned char c) { return char(std::tolower(c)); });
            origin = text;
        }
        if (hasUser) *hasUser = curlLibrary().url_get(u, CURLUPART_USER, &user, 0) == CURLUE_OK;
        curlLibrary().free(scheme);
        curlLibrary().free(host);
        curlLibrary().free(port);
        curlLibrary().free(user);
    }
    curlLibrary().url_cleanup(u);
    return origin;
}

int64_t retryAfterMs(const std::string& value) {
    constexpr int64_t kDayMs = int64_t(86400) * 1000;
    if (value.empty()) return 0;
    if (std::all_of(value.begin(), value.end(), [](unsigned char c) { return std::isdigit(c); }))
        return value.size() > 8 ? kDayMs : std::min(kDayMs, int64_t(std::stoll(value)) * 1000);
    const time_t at = curlLibrary().getdate(value.c_str(), nullptr);
    const time_t now = std::time(nullptr);
    return at > now ? std::min<int64_t>(int64_t(at - now), 86400) * 1000 : 0;
}

bool isRedirect(long status) {
    return status == 301 || status == 302 || status == 303 || status == 307 || status == 308;
}

}  // namespace vdiso::http_answer
