// Command-line parsing shared by the subcommands: a cursor over argv and value parsers that
// throw UsageError with one clear sentence. Each subcommand fills its own options struct.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "core/volume.h"
#include "io/remote/remote_options.h"
#include "io/store/store_writer.h"

namespace vdiso::cli {

// Wrong usage: printed with a hint to --help, exit code 2.
class UsageError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// The exit code of a command's exception, the same for vdiso and vdiso-mpi: 2 for wrong usage
// (UsageError, a SettingsError of app/extract_settings.h, a CacheBudgetError), 130 for an interrupt (core/interrupt.h: Ctrl-C or SIGTERM), 1 for any other.
int exitCodeOf(const std::exception& e);

// What a front end says of an exception: its message, with the option that sets what it is
// about where the library names a quantity (a CacheBudgetError: --cache-mb; an
// OutputExistsError: --force; a SettingsError: the flags of the settings it names).
std::string messageOf(const std::exception& e);

// The flags of settings named in snake case: "lod_error" -> "--lod-error", "smooth and
// min_piece" -> "--smooth and --min-piece".
std::string flagsOf(const std::string& settings);

class Args {
public:
    Args(int argc, char** argv, int first);
    bool done() const { return mAt >= mItems.size(); }
    const std::string& peek() const { return mItems[mAt]; }
    std::string take() { return mItems[mAt++]; }
    // The value after `flag`; throws UsageError if there is none.
    std::string value(const std::string& flag);

private:
    std::vector<std::string> mItems;
    size_t mAt = 0;
};

// Refuses, before any work, an output that exists when --force was not given: throws UsageError
// naming it. Empty paths and "-" (stdout) are passed over.
void refuseExistingOutputs(std::initializer_list<const std::string*> paths, bool overwrite);


int64_t parseInt(const std::string& flag, const std::string& text, int64_t lo, int64_t hi);
double parseDouble(const std::string& flag, const std::string& text);
// "N" (a cube) or "X,Y,Z".
Dims3 parseDims(const std::string& flag, const std::string& text);
// "S" (all axes) or "X,Y,Z", each positive.
glm::dvec3 parseSpacing(const std::string& flag, const std::string& text);

// The options every command that writes a brick store takes: --brick, --compress, --level,
// --no-shuffle, --force. Consumes `flag` (and its value) and returns true if it is one.
bool takeStoreWriteOption(const std::string& flag, Args& args, StoreWriteOptions& options);

// Help lines for those options.
extern const char* const kStoreWriteOptionsHelp;

// The options every command that reads a store takes for a remote one (http://, https://,
// s3://): --s3-endpoint, --s3-addressing, --no-sign-request, --ca-file, --remote-timeout, --remote-deadline,
// --connections. Consumes `flag` (and its value) and returns true if it is one.
bool takeRemoteOption(const std::string& flag, Args& args, RemoteOptions& options);
// Help lines for those options.
extern const char* const kRemoteOptionsHelp;

}  // namespace vdiso::cli
