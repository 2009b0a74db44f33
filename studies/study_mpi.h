// Studies over MPI ranks (OpenMPI): rank 0 coordinates and computes on its threads, every other rank
// asks it for groups of tasks as its threads free up (dynamic load balancing) and sends back results.
// Only rank 0 touches the output folder. MPI is initialised with MPI_THREAD_FUNNELED: only the main
// thread of a rank calls MPI; waiting polls with short sleeps, so an oversubscribed machine does not
// lose a core to a spinning receive.
#pragma once

#include "studies/study.h"

#include <optional>
#include <utility>

namespace armsim {

/// Reads the study file on every rank and runs it over MPI_COMM_WORLD (initialising and finalising
/// MPI). Returns the study and its outcome on rank 0, nothing on the other ranks. threads: per rank
/// (0: the node's cores shared by its ranks). An error on any rank (a file missing on one node, a
/// study that differs between ranks) is printed and aborts every rank (MPI_Abort) with exit code 1.
std::optional<std::pair<Study, StudyOutcome>> runStudyOnMpi(const std::string& studyFile, const StudyRunOptions& options);

/// MPI studies as a plugin of the armsim command (libarmsim_study_mpi.so, built when libopenmpi-dev is
/// present and loaded only under mpirun): the other commands start without libmpi and its libraries.
struct StudyMpiPlugin {
    int abiVersion = 0;  ///< kStudyMpiPluginAbi of the plugin's build
    std::optional<std::pair<Study, StudyOutcome>> (*runStudyOnMpi)(const std::string& studyFile,
                                                                   const StudyRunOptions& options) = nullptr;
    /// The plugin's own copy of requestInterruption (it links its own ground-floor code).
    void (*requestInterruption)(int sig) = nullptr;
};

constexpr int kStudyMpiPluginAbi = 2;
constexpr const char* kStudyMpiPluginFile = "libarmsim_study_mpi.so";
constexpr const char* kStudyMpiPluginSymbol = "armsim_get_study_mpi_plugin";

}  // namespace armsim

/// The plugin's entry point (kStudyMpiPluginSymbol).
extern "C" const armsim::StudyMpiPlugin* armsim_get_study_mpi_plugin();
