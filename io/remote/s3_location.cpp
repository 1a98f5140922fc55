#include "io/remote/s3_location.h"

#include <cstdlib>
#include <fstream>
#include <string_view>

#include "io/error.h"

namespace vdiso {
namespace {

std::string env(const char* name) {
    const char* v = std::getenv(name);
    return v ? std::string(v) : std::string();
}

std::string trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    return std::string(s);
}

// `key` of section `section` in an INI file as AWS's tools write them; "" when absent. A file
// that is not there is no error (no profile); one that cannot be read when named is.
std::string iniValue(const std::string& file, const std::string& section, const std::string& key,
                     bool named) {
    std::ifstream in(file);
    if (!in) {
        if (named) throwIoError(file, "cannot be read (named by the environment for S3 credentials)");
        return {};
    }
    std::string line, current;
    while (std::getline(in, line)) {
        const std::string t = trim(line);
        if (t.empty() || t[0] == '#' || t[0] == ';') continue;
        if (t.front() == '[' && t.back() == ']') {
            current = trim(std::string_view(t).substr(1, t.size() - 2));
            continue;
        }
        const size_t eq = t.find('=');
        if (current == section && eq != std::string::npos && trim(std::string_view(t).substr(0, eq)) == key)
            return trim(std::string_view(t).substr(eq + 1));
    }
    return {};
}

std::string homeFile(const char* variable, const char* relative, bool& named) {
    std::string path = env(variable);
    named = !path.empty();
    if (!named) path = env("HOME") + relative;
    return path;
}

}  // namespace

std::string s3EncodeKey(const std::string& key) {
    static const char* const kHex = "0123456789ABCDEF";
    std::string out;
    for (const unsigned char c : key) {
        if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' ||
            c == '.' || c == '_' || c == '~' || c == '/') {
            out += char(c);
        } else {
            out += '%';
            out += kHex[c >> 4];
            out += kHex[c & 15];
        }
    }
    return out;
}

void splitS3Url(const std::string& s3Url, std::string& bucket, std::string& key) {
    constexpr std::string_view kScheme = "s3://";
    if (s3Url.compare(0, kScheme.size(), kScheme) != 0)
        throwIoError(s3Url, "is not an s3://BUCKET/KEY location");
    const std::string rest = s3Url.substr(kScheme.size());
    const size_t slash = rest.find('/');
    bucket = rest.substr(0, slash);
    key = slash == std::string::npos ? std::string() : rest.substr(slash + 1);
    if (bucket.empty() || key.empty() || bucket.find_first_of("?#@: ") != std::string::npos)
        throwIoError(s3Url, "is not an s3://BUCKET/KEY location (a bucket and a key are needed)");
}

S3Location withKey(const S3Location& bucket, const std::string& key) {
    S3Location s = bucket;
    s.key = key;
    s.url = s.base + s3EncodeKey(key);
    return s;
}

S3Location resolveS3Location(const std::string& s3Url, const RemoteOptions& options) {
    S3Location s;
    splitS3Url(s3Url, s.bucket, s.key);

    const std::string profile = env("AWS_PROFILE").empty() ? "default" : env("AWS_PROFILE");
    bool credentialsNamed = false, configNamed = false;
    const std::string credentialsFile =
        homeFile("AWS_SHARED_CREDENTIALS_FILE", "/.aws/credentials", credentialsNamed);
    const std::string configFile = homeFile("AWS_CONFIG_FILE", "/.aws/config", configNamed);
    const std::string configSection = profile == "default" ? profile : "profile " + profile;

    s.region = env("AWS_REGION");
    if (s.region.empty()) s.region = env("AWS_DEFAULT_REGION");
    if (s.region.empty()) s.region = iniValue(configFile, configSection, "region", configNamed);
    if (s.region.empty()) s.region = "us-east-1";

    if (!options.anonymous) {
        s.accessKey = env("AWS_ACCESS_KEY_ID");
        s.secretKey = env("AWS_SECRET_ACCESS_KEY");
        s.sessionToken = env("AWS_SESSION_TOKEN");
        if (s.accessKey.empty()) {
            s.accessKey = iniValue(credentialsFile, profile, "aws_access_key_id", credentialsNamed);
            s.secretKey = iniValue(credentialsFile, profile, "aws_secret_access_key", credentialsNamed);
            s.sessionToken = iniValue(credentialsFile, profile, "aws_session_token", credentialsNamed);
        }
        if (!s.accessKey.empty() && s.secretKey.empty())
            throwIoError(s3Url, "has an access key id but no secret access key for profile '" +
                                    profile + "'");
    }

    std::string endpoint = options.s3Endpoint;
    if (endpoint.empty()) endpoint = env("AWS_ENDPOINT_URL_S3");
    if (endpoint.empty()) endpoint = env("AWS_ENDPOINT_URL");
    const bool aws = endpoint.empty();
    if (aws) endpoint = "https://s3." + s.region + ".amazonaws.com";
    while (!endpoint.empty() && endpoint.back() == '/') endpoint.pop_back();
    const size_t schemeEnd = endpoint.find("://");
    if (schemeEnd == std::string::npos || (endpoint.compare(0, schemeEnd, "http") != 0 &&
                                           endpoint.compare(0, schemeEnd, "https") != 0))
        throwIoError(endpoint, "is not an http:// or https:// S3 endpoint");
    bool virtualHost = options.s3Addressing == S3Addressing::VirtualHost;
    // Dotted bucket names do not match AWS's wildcard certificate: path style for those.
    if (options.s3Addressing == S3Addressing::Auto)
        virtualHost = aws && s.bucket.find('.') == std::string::npos;
    if (virtualHost)
        s.base = endpoint.substr(0, schemeEnd + 3) + s.bucket + "." + endpoint.substr(schemeEnd + 3) + "/";
    else
        s.base = endpoint + "/" + s.bucket + "/";
    s.url = s.base + s3EncodeKey(s.key);
    return s;
}

}  // namespace vdiso
