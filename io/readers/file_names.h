// Helpers for recognising input files by name.
#pragma once

#include <cctype>
#include <string>

namespace vdiso {

// True if `s` ends with `suffix`, ignoring ASCII case: names from other systems arrive as
// "BRAIN.HDR" as often as "brain.hdr".
inline bool endsWithIgnoreCase(const std::string& s, const std::string& suffix) {
    if (s.size() < suffix.size()) return false;
    const size_t start = s.size() - suffix.size();
    for (size_t i = 0; i < suffix.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(s[start + i])) !=
            std::tolower(static_cast<unsigned char>(suffix[i])))
            return false;
    return true;
}

}  // namespace vdiso
