// What an answer to one of io/remote/remote_file.h's ranged GETs says, read from its status,
// headers and body. Each function is total: text that does not parse gives the "nothing" value
// (empty, nullopt, 0), never an exception, so a hostile server's words stay data.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

namespace vdiso::http_answer {

// ": Code (Message)" of S3's XML error body (<Code>NoSuchKey</Code>...), or "" without one.
std::string s3ErrorText(const std::string& body);

// "bytes A-B/TOTAL" as {A, B, TOTAL} (the unit in any case, unsigned decimals); nullopt when it
// is not that (a sign, another character, B < A, or B >= TOTAL).
std::optional<std::array<uint64_t, 3>> parseContentRange(const std::string& text);

// " (Not Found)" and the like for the statuses an object store answers, "" for others.
const char* statusReason(long status);

// Where a URL's requests go, "scheme://host:port" in lower case (the scheme's default port when
// none is given); nullopt when it does not parse. *hasUser: whether it names a user.
std::optional<std::string> originOf(const std::string& url, bool* hasUser = nullptr);

// A Retry-After (seconds, or an HTTP date) in milliseconds from now, at most a day (any wait that
// long is past every deadline); 0 when absent, past or not understood.
int64_t retryAfterMs(const std::string& value);

// 301, 302, 303, 307 and 308: the answers whose Location is where to ask instead.
bool isRedirect(long status);

}  // namespace vdiso::http_answer
