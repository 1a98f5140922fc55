#include "io/readers/run_time_module.h"

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <vector>

#include "io/error.h"

namespace vdiso {
namespace {

std::vector<std::string> moduleCandidates(const std::string& fileName) {
    if (const char* dir = std::getenv("VDISO_MODULE_DIR")) return {std::string(dir) + "/" + fileName};
    std::vector<std::string> dirs;
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) dirs.push_back(exe.parent_path().string());
#ifdef VDISO_BUILD_MODULE_DIR
    dirs.emplace_back(VDISO_BUILD_MODULE_DIR);
#endif
    std::vector<std::string> paths;
    for (const std::string& d : dirs) paths.push_back(d + "/" + fileName);
    return paths;
}

struct Loaded {
    void* library = nullptr;
    std::string why;  // when library is null: what went wrong ("" if not found at all)
};

}  // namespace

void* runTimeModuleSymbol(const char* fileName, const char* symbol, const std::string& path,
                          const std::string& purpose) {
    static std::mutex mutex;
    static std::map<std::string, Loaded> modules;  // tried once each: a failure is remembered
    void* address = nullptr;
    std::string why;
    {
        const std::lock_guard<std::mutex> lock(mutex);
        auto [it, first] = modules.try_emplace(fileName);
        Loaded& m = it->second;
        if (first) {
            for (const std::string& candidate : moduleCandidates(fileName)) {
                if (::access(candidate.c_str(), R_OK) != 0) continue;
                m.library = ::dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
                if (m.library) break;
                const char* error = ::dlerror();
                m.why = error ? error : candidate + " did not load";
            }
        }
        if (m.library) {
            address = ::dlsym(m.library, symbol);
            if (!address) why = std::string("it has no ") + symbol;
        } else {
            why = m.why;
        }
    }
#if VDISO_READER_MODULES_BUILT
    constexpr const char* kWhere = " (the build puts it beside vdiso; VDISO_MODULE_DIR says where else to look)";
#else
    constexpr const char* kWhere =
        " (this vdiso was built without its reader modules, -DVDISO_READER_MODULES=OFF, as "
        "scripts/demo.sh builds it: scripts/setup.sh, then scripts/build.sh, builds them; "
        "VDISO_MODULE_DIR says where else to look)";
#endif
    if (!address)
        throwIoError(path, purpose + " needs the module " + fileName + ", which was not found or did not load" +
                               kWhere + (why.empty() ? std::string() : ": " + why));
    return address;
}

}  // namespace vdiso
