#include "io/readers/file_list.h"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <system_error>

#include "io/error.h"
#include "io/readers/file_names.h"

namespace vdiso {

namespace {

bool isDigit(char c) { return c >= '0' && c <= '9'; }

}  // namespace

bool naturalLess(const std::string& a, const std::string& b) {
    size_t i = 0, j = 0;
    while (i < a.size() && j < b.size()) {
        if (isDigit(a[i]) && isDigit(b[j])) {
            // Compare the digit runs as numbers without converting them: they may be longer
            // than any integer type.
            size_t iEnd = i, jEnd = j;
            while (iEnd < a.size() && isDigit(a[iEnd])) ++iEnd;
            while (jEnd < b.size() && isDigit(b[jEnd])) ++jEnd;
            size_t iSig = i, jSig = j;
            while (iSig + 1 < iEnd && a[iSig] == '0') ++iSig;
            while (jSig + 1 < jEnd && b[jSig] == '0') ++jSig;
            const size_t iLen = iEnd - iSig, jLen = jEnd - jSig;
            if (iLen != jLen) return iLen < jLen;
            const int c = a.compare(iSig, iLen, b, jSig, jLen);
            if (c != 0) return c < 0;
            // Equal numbers: fewer leading zeros first, so the order stays total.
            if (iEnd - i != jEnd - j) return iEnd - i < jEnd - j;
            i = iEnd;
            j = jEnd;
            continue;
        }
        if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
        ++i;
        ++j;
    }
    return a.size() - i < b.size() - j;
}

bool isGlobPattern(const std::string& path) {
    return path.find_first_of("*?[") != std::string::npos;
}

std::vector<std::string> listFolder(const std::string& dir, const std::vector<std::string>& suffixes) {
    std::vector<std::string> names;
    std::error_code ec;
    std::filesystem::directory_iterator it(dir, ec);
    if (ec) throwIoError(dir, "cannot list the folder: " + ec.message());
    for (; it != std::filesystem::directory_iterator(); it.increment(ec)) {
        if (ec) throwIoError(dir, "cannot list the folder: " + ec.message());
        const std::string name = it->path().filename().string();
        if (name.empty() || name[0] == '.') continue;
        std::error_code typeError;
        if (!it->is_regular_file(typeError)) continue;
        const bool wanted =
            suffixes.empty() || std::any_of(suffixes.begin(), suffixes.end(), [&](const auto& s) {
                return endsWithIgnoreCase(name, s);
            });
        if (wanted) names.push_back(name);
    }
    std::sort(names.begin(), names.end(), naturalLess);
    std::vector<std::string> paths;
    paths.reserve(names.size());
    for (const std::string& name : names) paths.push_back((std::filesystem::path(dir) / name).string());
    return paths;
}

std::vector<std::string> expandGlob(const std::string& pattern) {
    glob_t g{};
    const int rc = ::glob(pattern.c_str(), GLOB_NOSORT, nullptr, &g);
    std::vector<std::string> paths;
    if (rc == 0)
        for (size_t i = 0; i < g.gl_pathc; ++i) {
            std::error_code ec;
            if (std::filesystem::is_regular_file(g.gl_pathv[i], ec)) paths.emplace_back(g.gl_pathv[i]);
        }
    ::globfree(&g);
    if (rc == GLOB_NOSPACE) throwIoError(pattern, "out of memory expanding the pattern");
    if (rc == GLOB_ABORTED) throwIoError(pattern, "a folder of the pattern cannot be read");
    if (paths.empty()) throwIoError(pattern, "no file matches the pattern");
    // Natural order of the whole path: the files of one pattern differ where the pattern has
    // its wildcards, and digits there compare as numbers.
    std::sort(paths.begin(), paths.end(), naturalLess);
    return paths;
}

}  // namespace vdiso
