// Plugins of the armsim command: libraries loaded with dlopen only by the commands that need them
// (the renderer, MPI), so that every other command starts without their shared libraries.
#pragma once

#include <string>

namespace armsim {
struct RenderPlugin;
struct StudyMpiPlugin;
}

namespace armsim::cli {

/// The renderer (render/render_plugin.h). InputError naming `option` when it cannot be loaded (built
/// with -DARMSIM_RENDER=OFF, or the plugin file missing beside the executable).
const RenderPlugin& getRenderPlugin(const std::string& option);
/// The same InputError when the renderer plugin's file is not where getRenderPlugin looks, without
/// loading it (its libraries stay mapped once loaded: the main job loads it last).
void checkRenderPluginFile(const std::string& option);

/// Passes an interruption (SIGINT/SIGTERM) on to every plugin loaded now or later: each holds its own
/// copy of the interruption flag.
void forwardInterruption(int sig);

/// Studies over MPI ranks (studies/study_mpi.h). InputError saying how to get MPI when the
/// plugin is missing (built without libopenmpi-dev).
const StudyMpiPlugin& getStudyMpiPlugin();

}  // namespace armsim::cli
