#include "io/remote/curl_library.h"

#include <dlfcn.h>

#include <cstdlib>
#include <mutex>
#include <string>

#include "io/error.h"

namespace vdiso {
namespace {

constexpr const char* kSoname = "libcurl.so.4";

// Sets `member` to the library's function `name`; false when it has none.
template <class F>
bool bind(void* library, const char* name, F& member) {
    member = reinterpret_cast<F>(::dlsym(library, name));
    return member != nullptr;
}

}  // namespace

const CurlLibrary& curlLibrary() {
    static CurlLibrary curl;
    static std::string failure;  // set once when loading failed; asked again, the same answer
    static std::once_flag once;
    std::call_once(once, [] {
        // VDISO_CURL_LIBRARY: another file to load, for a system that keeps libcurl elsewhere.
        const char* other = std::getenv("VDISO_CURL_LIBRARY");
        const std::string soname = other && *other ? other : kSoname;
        void* library = ::dlopen(soname.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!library) {
            const char* why = ::dlerror();
            failure = "cannot load " + soname + " (libcurl, Debian's libcurl4; VDISO_CURL_LIBRARY names another)" +
                      (why ? std::string(": ") + why : "");
            return;
        }
        const char* missing = nullptr;
#define VDISO_CURL_BIND(name) \
    if (!missing && !bind(library, "curl_" #name, curl.name)) missing = "curl_" #name;
        VDISO_CURL_FUNCTIONS(VDISO_CURL_BIND)
#undef VDISO_CURL_BIND
        if (missing) {
            failure = soname + " has no " + missing + " (libcurl 7.85 or newer is needed)";
            return;
        }
        if (curl.global_init(CURL_GLOBAL_DEFAULT) != CURLE_OK) failure = "libcurl cannot be initialised";
    });
    if (!failure.empty()) throw IoError(failure + ": remote data cannot be read");
    return curl;
}

const CurlLibrary& curlLibraryFor(const std::string& location) {
    try {
        return curlLibrary();
    } catch (const IoError& e) {
        throwIoError(location, e.what());
    }
}

}  // namespace vdiso
