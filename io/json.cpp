#include "io/json.h"

#include <cmath>
#include <cstdio>

namespace vdiso {

std::string jsonQuote(const std::string& s) {
    std::string out = "\"";
    for (unsigned char c : s) {
        if (c == '"' || c == '\\') {
            out += '\\';
            out += char(c);
        } else if (c < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", c);
            out += buf;
        } else {
            out += char(c);
        }
    }
    return out + "\"";
}

void JsonObject::addKey(const std::string& key) {
    if (!mBody.empty()) mBody += ", ";
    mBody += jsonQuote(key) + ": ";
}

JsonObject& JsonObject::add(const std::string& key, const std::string& value) {
    addKey(key);
    mBody += jsonQuote(value);
    return *this;
}

std::string jsonNumber(double value) {
    if (!std::isfinite(value)) return "null";  // JSON has no NaN or infinity
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", value);
    return buf;
}

std::string jsonArray(std::span<const double> values) {
    std::string out = "[";
    for (size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + jsonNumber(values[i]);
    return out + "]";
}

JsonObject& JsonObject::add(const std::string& key, double value) {
    addKey(key);
    mBody += jsonNumber(value);
    return *this;
}

JsonObject& JsonObject::addExact(const std::string& key, double value) {
    addKey(key);
    if (!std::isfinite(value)) {
        mBody += "null";
    } else {
        char buf[40];
        std::snprintf(buf, sizeof buf, "%.17g", value);
        mBody += buf;
    }
    return *this;
}

JsonObject& JsonObject::add(const std::string& key, int64_t value) {
    addKey(key);
    mBody += std::to_string(value);
    return *this;
}

JsonObject& JsonObject::add(const std::string& key, uint64_t value) {
    addKey(key);
    mBody += std::to_string(value);
    return *this;
}

JsonObject& JsonObject::add(const std::string& key, bool value) {
    addKey(key);
    mBody += value ? "true" : "false";
    return *this;
}

JsonObject& JsonObject::addRaw(const std::string& key, const std::string& json) {
    addKey(key);
    mBody += json;
    return *this;
}

}  // namespace vdiso
