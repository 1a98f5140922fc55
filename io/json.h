// One JSON object on one line, built field by field: the format of every machine-readable
// output (`info --json`, `--stats`). Keys keep insertion order.
#pragma once

#include <cstdint>
#include <span>
#include <string>

namespace vdiso {

class JsonObject {
public:
    JsonObject& add(const std::string& key, const std::string& value);
    JsonObject& add(const std::string& key, const char* value) { return add(key, std::string(value)); }
    JsonObject& add(const std::string& key, double value);
    // A double written with 17 significant digits, so that it reads back bit-exactly (values
    // a reader compares for equality, such as an isovalue that keys cached chunks).
    JsonObject& addExact(const std::string& key, double value);
    JsonObject& add(const std::string& key, int64_t value);
    JsonObject& add(const std::string& key, uint64_t value);
    JsonObject& add(const std::string& key, int value) { return add(key, int64_t(value)); }
    JsonObject& add(const std::string& key, bool value);
    // `json` must itself be valid JSON (an array or a nested object).
    JsonObject& addRaw(const std::string& key, const std::string& json);
    std::string str() const { return "{" + mBody + "}"; }

private:
    void addKey(const std::string& key);
    std::string mBody;
};

// `s` as a JSON string literal, quotes included.
std::string jsonQuote(const std::string& s);
// A number as every writer here prints it (9 significant digits; null for NaN and infinity),
// and an array of them.
std::string jsonNumber(double value);
std::string jsonArray(std::span<const double> values);

}  // namespace vdiso
