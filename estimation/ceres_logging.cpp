#include "estimation/ceres_logging.h"

#include <glog/logging.h>

namespace armsim {

void quietCeresLogging() {
    static const bool quiet = (FLAGS_minloglevel = google::GLOG_FATAL, true);
    (void)quiet;
}

}  // namespace armsim
