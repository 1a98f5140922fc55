#include "tools/args.h"

#include <charconv>
#include <cmath>
#include <sstream>

namespace vdiso::cli {

Args::Args(int argc, char** argv, int first) {
    for (int i = first; i < argc; ++i) mItems.emplace_back(argv[i]);
}

std::string Args::value(const std::string& flag) {
    if (done()) throw UsageError(flag + " needs a value");
    return take();
}

namespace {

std::vector<std::string> splitCommas(const std::string& text) {
    std::vector<std::string> parts;
    std::stringstream ss(text);
    std::string part;
    while (std::getline(ss, part, ',')) parts.push_back(part);
    if (!text.empty() && text.back() == ',') parts.push_back("");
    return parts;
}

}  // namespace

int64_t parseInt(const std::string& flag, const std::string& text, int64_t lo, int64_t hi) {
    int64_t v = 0;
    auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size())
        throw UsageError(flag + " expects a whole number, not '" + text + "'");
    if (v < lo || v > hi)
        throw UsageError(flag + " must be between " + std::to_string(lo) + " and " +
                         std::to_string(hi) + ", not " + text);
    return v;
}

double parseDouble(const std::string& flag, const std::string& text) {
    double v = 0;
    auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v))
        throw UsageError(flag + " expects a number, not '" + text + "'");
    return v;
}

Dims3 parseDims(const std::string& flag, const std::string& text) {
    const auto parts = splitCommas(text);
    if (parts.size() != 1 && parts.size() != 3)
        throw UsageError(flag + " expects N or X,Y,Z, not '" + text + "'");
    Dims3 d;
    for (int a = 0; a < 3; ++a)
        d[a] = parseInt(flag, parts[parts.size() == 1 ? 0 : a], 2, int64_t(1) << 31);
    return d;
}

glm::dvec3 parseSpacing(const std::string& flag, const std::string& text) {
    const auto parts = splitCommas(text);
    if (parts.size() != 1 && parts.size() != 3)
        throw UsageError(flag + " expects S or X,Y,Z, not '" + text + "'");
    glm::dvec3 s;
    for (int a = 0; a < 3; ++a) {
        s[a] = parseDouble(flag, parts[parts.size() == 1 ? 0 : a]);
        if (s[a] <= 0) throw UsageError(flag + " values must be positive");
    }
    return s;
}

}  // namespace vdiso::cli
