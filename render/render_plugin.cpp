#include "render/render_plugin.h"

#include "basics/errors.h"

extern "C" __attribute__((visibility("default"))) const armsim::RenderPlugin* armsim_get_render_plugin() {
    static const armsim::RenderPlugin plugin = [] {
        armsim::RenderPlugin p;
        p.abiVersion = armsim::kRenderPluginAbi;
        p.renderTrialVideo = [](const armsim::ArmSetup& setup, const armsim::Table& table,
                                const armsim::TrialVideoSettings& settings, const std::function<void(int, int)>& progress) {
            return armsim::renderTrialVideo(setup, table, settings, progress);
        };
        p.readRenderSettings = &armsim::readRenderSettings;
        p.validate = [](const armsim::TrialVideoSettings& s) { s.validate(); };
        p.renderOsimTrialVideo = [](const armsim::OsimModel& model, const armsim::Table& table,
                                    const armsim::OsimVideoSettings& settings, const std::function<void(int, int)>& progress) {
            return armsim::renderOsimTrialVideo(model, table, settings, progress);
        };
        p.validateOsim = [](const armsim::OsimVideoSettings& s) { s.validate(); };
        p.requestInterruption = &armsim::requestInterruption;
        return p;
    }();
    return &plugin;
}
