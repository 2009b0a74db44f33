// Studies over MPI ranks (OpenMPI): rank 0 coordinates and computes on its threads, every other rank
// asks it for groups of tasks as its threads free up (dynamic load balancing) and sends back results.
// Only rank 0 touches the output folder. MPI is initialised with MPI_THREAD_FUNNELED: only the main
// thread of a rank calls MPI; waiting polls with short sleeps, so an oversubscribed machine does not
// lose a core to a spinning receive.
#pragma once

#include "identification/study.h"

#include <optional>
#include <utility>

namespace armsim {

/// true when armsim was built with MPI.
bool hasMpi();

/// Reads the study file on every rank and runs it over MPI_COMM_WORLD (initialising and finalising
/// MPI). Returns the study and its outcome on rank 0, nothing on the other ranks. threads: per rank
/// (0: the node's cores shared by its ranks). An error on any rank (a file missing on one node, a
/// study that differs between ranks) is printed and aborts every rank (MPI_Abort) with exit code 1.
std::optional<std::pair<Study, StudyOutcome>> runStudyOnMpi(const std::string& studyFile, const StudyRunOptions& options);

}  // namespace armsim
