// Stand-in for study_mpi.cpp when armsim is built without MPI: studies run on threads only.
#include "identification/study_mpi.h"

#include "muscles/param_file.h"

namespace armsim {

bool hasMpi() { return false; }

std::optional<std::pair<Study, StudyOutcome>> runStudyOnMpi(const std::string&, const StudyRunOptions&) {
    throw InputError("this armsim was built without MPI (install libopenmpi-dev and rebuild); run the study "
                     "without mpirun to use threads");
}

}  // namespace armsim
