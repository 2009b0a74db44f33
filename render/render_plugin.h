// The renderer as a plugin of the armsim command (libarmsim_render_plugin.so, loaded with dlopen by
// cli/plugins.h when a command renders). OSMesa, LLVM and OpenCV's video stack bring about 230 shared
// libraries whose loading and symbol binding cost every start of the command about 0.3 s; a command
// that does not render no longer loads them. The plugin holds its own copy of the model code; the
// structures passed across are compiled from the same headers.
#pragma once

#include "render/osim_video.h"
#include "render/trial_video.h"

#include <functional>

namespace armsim {

/// What the plugin offers (function pointers into the plugin).
struct RenderPlugin {
    int abiVersion = 0;  ///< kRenderPluginAbi of the plugin's build
    TrialVideoResult (*renderTrialVideo)(const ArmSetup& setup, const Table& table, const TrialVideoSettings& settings,
                                         const std::function<void(int, int)>& progress) = nullptr;
    RenderSettings (*readRenderSettings)(const ParamNode& node) = nullptr;
    void (*validate)(const TrialVideoSettings& settings) = nullptr;  ///< TrialVideoSettings::validate
    OsimVideoResult (*renderOsimTrialVideo)(const OsimModel& model, const Table& table, const OsimVideoSettings& settings,
                                            const std::function<void(int, int)>& progress) = nullptr;
    void (*validateOsim)(const OsimVideoSettings& settings) = nullptr;  ///< OsimVideoSettings::validate
    /// The plugin's own copy of requestInterruption (it links its own ground-floor code).
    void (*requestInterruption)(int sig) = nullptr;
};

constexpr int kRenderPluginAbi = 3;                          ///< raised when RenderPlugin changes
constexpr const char* kRenderPluginFile = "libarmsim_render_plugin.so";
constexpr const char* kRenderPluginSymbol = "armsim_get_render_plugin";

}  // namespace armsim

/// The plugin's entry point (kRenderPluginSymbol).
extern "C" const armsim::RenderPlugin* armsim_get_render_plugin();
