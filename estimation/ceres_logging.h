// Ceres logs through glog to stderr (a singular covariance, a failed step); armsim reports those
// conditions in its own messages, so glog is kept quiet below FATAL.
#pragma once

namespace armsim {

/// Silences glog below FATAL (idempotent, thread-safe). Call before any Ceres solve or covariance.
void quietCeresLogging();

}  // namespace armsim
