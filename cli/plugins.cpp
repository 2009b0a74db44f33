#include "cli/plugins.h"

#include "basics/errors.h"
#include "basics/files.h"
#include "studies/study_mpi.h"

#ifdef ARMSIM_WITH_RENDER
#include "render/render_plugin.h"
#endif

#include <dlfcn.h>

#include <filesystem>
#include <algorithm>
#include <mutex>
#include <vector>

namespace armsim::cli {

namespace {

std::mutex gMutex;      // the interruption sinks
std::mutex gLoadMutex;  // dlopen and the lookup
std::vector<void (*)(int)> gInterruptionSinks;  // the loaded plugins' requestInterruption
int gForwarded = 0;

/// The folder of the running executable (plugins are built beside it); empty when unknown (then no
/// plugin is loaded: never from the current folder).
std::string findExecutableFolder() {
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    return ec ? std::string() : exe.parent_path().string();
}

void addInterruptionSink(void (*sink)(int)) {
    if (!sink) return;
    const std::lock_guard<std::mutex> lock(gMutex);
    gInterruptionSinks.push_back(sink);
    if (gForwarded) sink(gForwarded);
}

// Where a plugin file may be: beside the executable (the build tree), or <prefix>/lib/armsim/ for
// <prefix>/bin/armsim (installed).
std::vector<std::string> findPluginCandidates(const std::string& folder, const char* file) {
    return {folder + "/" + file, folder + "/../lib/armsim/" + file};
}

/// dlopen(file beside the executable, else ARMSIM_PLUGIN_DIR/file) and dlsym(symbol); the entry
/// point's result, or nullptr with `why` set. The entry point is called through its own type
/// (`const Api* (*)()`): calling it through another function type is undefined behaviour.
template <class Api>
const Api* loadPluginApi(const char* file, const char* symbol, std::string& why) {
    const std::lock_guard<std::mutex> lock(gLoadMutex);
    static const Api* loaded = nullptr;  // one load per process; later calls reuse it
    if (loaded) return loaded;
    const std::string folder = findExecutableFolder();
    if (folder.empty()) {
        why = "the executable's folder is unknown (/proc/self/exe unreadable)";
        return nullptr;
    }
    const std::vector<std::string> candidates = findPluginCandidates(folder, file);
    for (const std::string& path : candidates) {
        if (!doesPathExist(path)) continue;
        void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            why = "cannot load " + path + ": " + dlerror();
            return nullptr;
        }
        using Entry = const Api* (*)();
        const auto entry = reinterpret_cast<Entry>(dlsym(handle, symbol));
        if (!entry) {
            why = path + " has no entry point " + symbol;
            return nullptr;
        }
        return loaded = entry();  // the handle stays open for the process's life
    }
    why = std::string(file) + " not found beside the executable (" + candidates[0] + ")";
    return nullptr;
}

}  // namespace

void forwardInterruption(int sig) {
    const std::lock_guard<std::mutex> lock(gMutex);
    gForwarded = sig;
    for (void (*sink)(int) : gInterruptionSinks) sink(sig);
}

void checkRenderPluginFile(const std::string& option) {
#ifdef ARMSIM_WITH_RENDER
    const std::string folder = findExecutableFolder();
    const std::vector<std::string> candidates = findPluginCandidates(folder, kRenderPluginFile);
    if (!folder.empty() && std::none_of(candidates.begin(), candidates.end(), [](const std::string& p) { return doesPathExist(p); }))
        throw InputError(option + ": the renderer plugin is missing: " + kRenderPluginFile + " not found beside the executable (" +
                         candidates[0] + ")");
#else
    throw InputError(option + ": this armsim was built without the renderer (-DARMSIM_RENDER=OFF)");
#endif
}

const RenderPlugin& getRenderPlugin(const std::string& option) {
#ifdef ARMSIM_WITH_RENDER
    std::string why;
    const RenderPlugin* p = loadPluginApi<RenderPlugin>(kRenderPluginFile, kRenderPluginSymbol, why);
    if (!p) throw InputError(option + ": the renderer plugin is missing: " + why);
    if (p->abiVersion != kRenderPluginAbi)
        throw InputError(option + ": the renderer plugin is from another build (interface " +
                         std::to_string(p->abiVersion) + ", expected " + std::to_string(kRenderPluginAbi) + "): rebuild");
    static std::once_flag once;
    std::call_once(once, [p] { addInterruptionSink(p->requestInterruption); });
    return *p;
#else
    throw InputError(option + ": this armsim was built without the renderer (-DARMSIM_RENDER=OFF)");
#endif
}

const StudyMpiPlugin& getStudyMpiPlugin() {
    std::string why;
    const StudyMpiPlugin* p = loadPluginApi<StudyMpiPlugin>(kStudyMpiPluginFile, kStudyMpiPluginSymbol, why);
    if (!p)
        throw InputError("this armsim has no MPI (" + why + "; install libopenmpi-dev and rebuild); run the study "
                         "without mpirun to use threads");
    if (p->abiVersion != kStudyMpiPluginAbi) throw InputError("the MPI plugin is from another build: rebuild");
    static std::once_flag once;
    std::call_once(once, [p] { addInterruptionSink(p->requestInterruption); });
    return *p;
}

}  // namespace armsim::cli
