// libFuzzer target for armsim's file loaders (issue 15). One binary, the loader chosen by the
// ARMSIM_FUZZ_LOADER environment variable (muscle, arm, model, osim, protocol, torque_protocol, population,
// study, force_csv, torque_csv, channel_csv, sto, trace, study_journal, forward_setup, anatomy_targets). Each input is written to a scratch file and loaded; a loader
// may reject it only with InputError (bad input) or SimulationError (a model it cannot solve). Any
// other exception, a crash, a hang or a sanitizer report is a finding.
#include "basics/errors.h"
#include "basics/files.h"
#include "basics/storage_file.h"
#include "experiments/population.h"
#include "experiments/protocol.h"
#include "experiments/channels.h"
#include "experiments/torque_protocol.h"
#include "identification/observations.h"
#include "studies/study.h"
#include "model/anatomy_targets.h"
#include "model/arm_parameters.h"
#include "model/model_file.h"
#include "model/osim_file.h"
#include "model/osim_forward.h"
#include "muscles/activation.h"
#include "muscles/muscle_file.h"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <string>

namespace {

using Loader = std::function<void(const std::string& path)>;

const std::map<std::string, std::pair<std::string, Loader>>& getLoaders() {
    using namespace armsim;
    static const std::map<std::string, std::pair<std::string, Loader>> loaders = {
        {"muscle", {".yaml", [](const std::string& p) { loadMuscleParameters(p); }}},
        {"arm", {".yaml", [](const std::string& p) { loadArmParameters(p); }}},
        {"model", {".yaml", [](const std::string& p) { loadModel(p); }}},
        {"osim", {".osim", [](const std::string& p) { readOsimFile(p); }}},
        {"anatomy_targets", {".yaml", [](const std::string& p) { loadAnatomyTargets(p); }}},
        {"forward_setup", {".xml", [](const std::string& p) { readOsimForwardSetup(p); }}},
        {"protocol", {".yaml", [](const std::string& p) { loadProtocolSubject(readProtocol(p)); }}},
        {"torque_protocol", {".yaml", [](const std::string& p) { readTorqueProtocol(p); }}},
        {"population", {".yaml", [](const std::string& p) { loadPopulation(p); }}},
        {"study", {".yaml", [](const std::string& p) { readStudy(p); }}},
        {"force_csv", {".csv", [](const std::string& p) { readObservations(p); }}},
        {"torque_csv", {".csv", [](const std::string& p) { readTorqueData(p); }}},
        {"channel_csv", {".csv", [](const std::string& p) { readChannelData(p); }}},
        {"sto", {".sto", [](const std::string& p) { readStorage(p); }}},
        {"trace", {".csv", [](const std::string& p) { loadActivationTrace(p); }}},
        {"study_journal", {".log", [](const std::string& p) {  // a study's journal.log, header line included
             const StudyJournal j = parseStudyJournal(readFileText(p), 1000, 1);
             summarizeStudyJournalDrops(j.dropped, &j);
             formatStudyJournalDrops(j.dropped);
         }}},
    };
    return loaders;
}

std::string gPath;
const Loader* gLoader = nullptr;

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    const char* name = std::getenv("ARMSIM_FUZZ_LOADER");
    const auto& loaders = getLoaders();
    const auto it = loaders.find(name ? name : "");
    if (it == loaders.end()) {
        std::fprintf(stderr, "ARMSIM_FUZZ_LOADER = '%s': expected one of", name ? name : "");
        for (const auto& [key, value] : loaders) std::fprintf(stderr, " %s", key.c_str());
        std::fprintf(stderr, "\n");
        std::exit(2);
    }
    gPath = "/tmp/armsim_fuzz_" + std::to_string(::getpid()) + it->second.first;
    gLoader = &it->second.second;
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    {
        std::ofstream out(gPath, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    }
    try {
        (*gLoader)(gPath);
    } catch (const armsim::InputError&) {
    } catch (const armsim::SimulationError&) {
    }
    return 0;
}
