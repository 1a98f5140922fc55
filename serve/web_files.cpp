#include "serve/web_files.h"

#include <filesystem>
#include <fstream>

#include "io/error.h"

namespace vdiso::serve {

namespace fs = std::filesystem;

namespace {

std::string contentTypeOf(const fs::path& file) {
    const std::string ext = file.extension().string();
    if (ext == ".html") return "text/html; charset=utf-8";
    if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
    if (ext == ".css") return "text/css; charset=utf-8";
    if (ext == ".png") return "image/png";
    if (ext == ".svg") return "image/svg+xml";
    return "application/octet-stream";
}

}  // namespace

WebFiles::WebFiles(const std::string& webRoot) : mRoot(webRoot) {
    const fs::path root(webRoot);
    auto add = [&](const std::string& url, const fs::path& file, bool required) {
        if (!fs::is_regular_file(file)) {
            if (!required) return;
            throw IoError(webRoot + ": the viewer's file " + fs::relative(file, root).string() +
                          " is missing (scripts/setup.sh installs the page's modules with npm ci)");
        }
        mFiles[url] = {file.string(), contentTypeOf(file)};
    };
    add("/", root / "index.html", true);
    add("/index.html", root / "index.html", true);
    add("/style.css", root / "style.css", false);
    std::error_code error;
    for (const fs::directory_entry& e : fs::directory_iterator(root / "src", error))
        if (e.is_regular_file() && e.path().extension() == ".js")
            add("/src/" + e.path().filename().string(), e.path(), true);
    if (error) throw IoError(webRoot + "/src: cannot be listed: " + error.message());
    const fs::path modules = root / "node_modules";
    add("/vendor/three.module.js", modules / "three/build/three.module.js", true);
    add("/vendor/three.core.js", modules / "three/build/three.core.js", false);
    add("/vendor/OrbitControls.js", modules / "three/examples/jsm/controls/OrbitControls.js", true);
    add("/vendor/meshopt_decoder.module.js", modules / "meshoptimizer/meshopt_decoder.mjs", true);
}

std::optional<WebFile> WebFiles::find(const std::string& urlPath) const {
    const auto it = mFiles.find(urlPath);
    if (it == mFiles.end()) return std::nullopt;
    return it->second;
}

std::optional<std::string> findParameter(const std::string& text, const std::string& name, char separator) {
    size_t start = 0;
    while (start <= text.size()) {
        size_t end = text.find(separator, start);
        if (end == std::string::npos) end = text.size();
        std::string item = text.substr(start, end - start);
        const size_t first = item.find_first_not_of(' ');
        item = first == std::string::npos ? "" : item.substr(first);
        const size_t eq = item.find('=');
        if (eq != std::string::npos && item.compare(0, eq, name) == 0 && eq == name.size())
            return item.substr(eq + 1);
        start = end + 1;
    }
    return std::nullopt;
}

bool constantTimeEquals(const std::string& a, const std::string& b) {
    unsigned char diff = a.size() == b.size() ? 0 : 1;
    for (size_t i = 0; i < a.size(); ++i) diff |= uint8_t(a[i] ^ (i < b.size() ? b[i] : 0));
    return diff == 0;
}

std::string randomToken() {
    std::ifstream in("/dev/urandom", std::ios::binary);
    unsigned char bytes[16];
    if (!in.read(reinterpret_cast<char*>(bytes), sizeof bytes))
        throw IoError("/dev/urandom: cannot read a random token");
    static const char* kHex = "0123456789abcdef";
    std::string token;
    for (const unsigned char b : bytes) {
        token += kHex[b >> 4];
        token += kHex[b & 15];
    }
    return token;
}

}  // namespace vdiso::serve
