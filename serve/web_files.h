// The viewer's files, the only files the server serves: a fixed table from URL path to file,
// made at start from the web folder (web/: index.html, style.css, src/*.js, and the few
// three.js and meshoptimizer modules the page imports from web/node_modules). Requests are
// matched against the table only, never mapped onto the file system, so no path can leave it
// and no folder is listed.
#pragma once

#include <map>
#include <optional>
#include <string>

namespace vdiso::serve {

struct WebFile {
    std::string path;         // on disk
    std::string contentType;  // "text/javascript; charset=utf-8", ...
};

class WebFiles {
public:
    // Builds the table. Throws IoError naming the folder and the missing file when the page
    // or one of its modules is absent (node_modules missing: scripts/setup.sh installs them).
    explicit WebFiles(const std::string& webRoot);

    // The file for a URL path ("/", "/src/viewer.js", ...), or nothing.
    std::optional<WebFile> find(const std::string& urlPath) const;
    const std::string& root() const { return mRoot; }

private:
    std::string mRoot;
    std::map<std::string, WebFile> mFiles;
};

// The value of `name` in a URL query ("a=1&token=x") or a Cookie header ("a=1; token=x"), or
// nothing. `separator` is '&' for queries and ';' for cookies. No percent-decoding: the values
// looked up here (tokens) are plain hex.
std::optional<std::string> findParameter(const std::string& text, const std::string& name, char separator);

// Compares in time independent of where the strings differ (tokens).
bool constantTimeEquals(const std::string& a, const std::string& b);

// 32 hex characters from the system's random source. Throws IoError if it cannot be read.
std::string randomToken();

}  // namespace vdiso::serve
