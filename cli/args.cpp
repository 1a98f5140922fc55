#include "cli/args.h"

#include "app/extract_settings.h"
#include "cache/brick_cache.h"
#include "core/interrupt.h"
#include "io/atomic_output.h"
#include "io/readers/dicom_series.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <thread>

namespace vdiso::cli {

std::string flagsOf(const std::string& settings) {
    std::string out, word;
    auto flush = [&] {
        if (word.empty()) return;
        if (word == "and") out += word;
        else {
            std::replace(word.begin(), word.end(), '_', '-');
            out += "--" + word;
        }
        word.clear();
    };
    for (char c : settings) {
        if ((c >= 'a' && c <= 'z') || c == '_') word += c;
        else {
            flush();
            out += c;
        }
    }
    flush();
    return out;
}

std::string messageOf(const std::exception& e) {
    if (auto* s = dynamic_cast<const SettingsError*>(&e)) return flagsOf(s->setting()) + " " + s->what();
    std::string message = e.what();
    if (dynamic_cast<const CacheBudgetError*>(&e)) message += " (--cache-mb)";
    if (dynamic_cast<const OutputExistsError*>(&e)) message += " (pass --force to replace it)";
    if (dynamic_cast<const DicomSeriesChoiceError*>(&e)) message += "\n(choose one with --series UID)";
    return message;
}

int exitCodeOf(const std::exception& e) {
    if (dynamic_cast<const UsageError*>(&e) || dynamic_cast<const SettingsError*>(&e) ||
        dynamic_cast<const CacheBudgetError*>(&e))
        return 2;
    if (dynamic_cast<const Interrupted*>(&e)) return 130;
    return 1;
}

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

void refuseExistingOutputs(std::initializer_list<const std::string*> paths, bool overwrite) {
    if (overwrite) return;
    for (const std::string* p : paths)
        if (!p->empty() && *p != "-")
            if (FILE* f = std::fopen(p->c_str(), "r")) {
                std::fclose(f);
                throw UsageError(*p + " already exists (pass --force to replace it)");
            }
}

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

const char* const kStoreWriteOptionsHelp =
    "  --brick B               cells per brick side (default 32)\n"
    "  --compress C            brick compression: lz4 (default), zstd or none; zstd stores\n"
    "                          about a quarter fewer bytes, lz4 decodes about 5x faster\n"
    "  --level N               zstd level (default 1)\n"
    "  --no-shuffle            compress multi-byte samples without the byte-shuffle filter\n"
    "  --levels N|auto         levels of detail beyond the full resolution, each with cells\n"
    "                          twice as large (default auto: until the coarsest is one\n"
    "                          brick, about 1/7 more bytes); 0 for none\n"
    "  --force                 replace OUTPUT if it exists\n";

bool takeStoreWriteOption(const std::string& flag, Args& args, StoreWriteOptions& options) {
    if (flag == "--brick") {
        options.brickSize = int(parseInt(flag, args.value(flag), 2, 512));
    } else if (flag == "--compress") {
        const std::string c = args.value(flag);
        const std::optional<Compression> codec = parseCompression(c);
        if (!codec) throw UsageError("--compress expects zstd, lz4 or none, not '" + c + "'");
        options.compression = *codec;
    } else if (flag == "--level") {
        options.compressionLevel = int(parseInt(flag, args.value(flag), -7, 19));
    } else if (flag == "--levels") {
        const std::string v = args.value(flag);
        options.coarseLevels = v == "auto" ? StoreWriteOptions::kLevelsUntilOneBrick
                                           : int(parseInt(flag, v, 0, kMaxLevels - 1));
    } else if (flag == "--no-shuffle") {
        options.shuffle = false;
    } else if (flag == "--force") {
        options.overwrite = true;
    } else {
        return false;
    }
    return true;
}

const char* const kRemoteOptionsHelp =
    "remote data (a store as https://HOST/PATH.vdiso, http://... or s3://BUCKET/KEY.vdiso; for\n"
    "convert, a Zarr or OME-Zarr at such a URL):\n"
    "  --s3-endpoint URL       S3 endpoint (default AWS_ENDPOINT_URL_S3, AWS_ENDPOINT_URL, else\n"
    "                          AWS's for the region: AWS_REGION, AWS_DEFAULT_REGION, the profile's)\n"
    "  --s3-addressing path|virtual   bucket in the path or in the host name (default: virtual\n"
    "                          on AWS, path on other endpoints)\n"
    "  --no-sign-request       anonymous requests (public buckets); otherwise credentials from\n"
    "                          AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY, AWS_SESSION_TOKEN or\n"
    "                          the AWS_PROFILE profile of ~/.aws/credentials\n"
    "  --ca-file FILE          CA certificates for HTTPS (default AWS_CA_BUNDLE, else the system's)\n"
    "  --remote-timeout S      seconds without a byte before a request is tried again (default 15)\n"
    "  --remote-deadline S     seconds one read may take in all, tries and pauses included\n"
    "                          (default 60): a server that drips bytes is ended by it\n"
    "  --connections N         requests in flight at once (default 32)\n"
    "  --disk-cache DIR        keep fetched bricks in DIR across runs and processes, for the\n"
    "                          object's current version (its ETag)\n"
    "  --disk-cache-mb N       at most N MB in DIR (default 10240): least recently used go first\n";

bool takeRemoteOption(const std::string& flag, Args& args, RemoteOptions& options) {
    if (flag == "--s3-endpoint") {
        options.s3Endpoint = args.value(flag);
    } else if (flag == "--s3-addressing") {
        const std::string v = args.value(flag);
        if (v == "path")
            options.s3Addressing = S3Addressing::Path;
        else if (v == "virtual")
            options.s3Addressing = S3Addressing::VirtualHost;
        else
            throw UsageError("--s3-addressing expects path or virtual, not '" + v + "'");
    } else if (flag == "--no-sign-request") {
        options.anonymous = true;
    } else if (flag == "--ca-file") {
        options.caFile = args.value(flag);
    } else if (flag == "--remote-timeout") {
        options.stallTimeoutMs = 1000 * parseInt(flag, args.value(flag), 1, 3600);
    } else if (flag == "--remote-deadline") {
        options.deadlineMs = 1000 * parseInt(flag, args.value(flag), 1, 86400);
    } else if (flag == "--connections") {
        options.connections = int(parseInt(flag, args.value(flag), 1, 256));
    } else if (flag == "--disk-cache") {
        options.diskCacheDir = args.value(flag);
    } else if (flag == "--disk-cache-mb") {
        options.diskCacheBytes = uint64_t(parseInt(flag, args.value(flag), 1, int64_t(1) << 30)) << 20;
    } else {
        return false;
    }
    return true;
}

}  // namespace vdiso::cli
