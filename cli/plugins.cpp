#include "cli/plugins.h"

#include "identification/study_mpi.h"
#include "muscles/param_file.h"

#ifdef ARMSIM_WITH_RENDER
#include "render/render_plugin.h"
#endif

#include <dlfcn.h>

#include <filesystem>
#include <mutex>

namespace armsim::cli {

namespace {

/// The folder of the running executable (plugins are built beside it).
std::string findExecutableFolder() {
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    return ec ? std::string(".") : exe.parent_path().string();
}

/// dlopen(file beside the executable, else ARMSIM_PLUGIN_DIR/file) and dlsym(symbol); the entry
/// point's result, or nullptr with `why` set.
const void* loadPluginApi(const char* file, const char* symbol, std::string& why) {
    static std::mutex mutex;
    const std::lock_guard<std::mutex> lock(mutex);
    std::vector<std::string> candidates = {findExecutableFolder() + "/" + file};
#ifdef ARMSIM_PLUGIN_DIR
    candidates.push_back(std::string(ARMSIM_PLUGIN_DIR) + "/" + file);
#endif
    for (const std::string& path : candidates) {
        if (!std::filesystem::exists(path)) continue;
        void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            why = "cannot load " + path + ": " + dlerror();
            return nullptr;
        }
        using Entry = const void* (*)();
        const auto entry = reinterpret_cast<Entry>(dlsym(handle, symbol));
        if (!entry) {
            why = path + " has no entry point " + symbol;
            return nullptr;
        }
        return entry();  // the handle stays open for the process's life
    }
    why = std::string(file) + " not found beside the executable (" + candidates[0] + ")";
    return nullptr;
}

}  // namespace

const RenderPlugin& getRenderPlugin(const std::string& option) {
#ifdef ARMSIM_WITH_RENDER
    std::string why;
    const auto* p = static_cast<const RenderPlugin*>(loadPluginApi(kRenderPluginFile, kRenderPluginSymbol, why));
    if (!p) throw InputError(option + ": the renderer plugin is missing: " + why);
    if (p->abiVersion != kRenderPluginAbi)
        throw InputError(option + ": the renderer plugin is from another build (interface " +
                         std::to_string(p->abiVersion) + ", expected " + std::to_string(kRenderPluginAbi) + "): rebuild");
    return *p;
#else
    throw InputError(option + ": this armsim was built without the renderer (-DARMSIM_RENDER=OFF)");
#endif
}

const StudyMpiPlugin& getStudyMpiPlugin() {
    std::string why;
    const auto* p = static_cast<const StudyMpiPlugin*>(loadPluginApi(kStudyMpiPluginFile, kStudyMpiPluginSymbol, why));
    if (!p)
        throw InputError("this armsim has no MPI (" + why + "; install libopenmpi-dev and rebuild); run the study "
                         "without mpirun to use threads");
    if (p->abiVersion != kStudyMpiPluginAbi) throw InputError("the MPI plugin is from another build: rebuild");
    return *p;
}

}  // namespace armsim::cli
