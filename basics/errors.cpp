#include "basics/errors.h"

#include <atomic>

namespace armsim {

namespace {
std::atomic<int> interruption{0};
}

FieldError::FieldError(std::string field, const std::string& message)
    : InputError("field '" + field + "' " + message), field_(std::move(field)), detail_(message) {}

void requestInterruption(int sig) { interruption.store(sig); }
int getInterruption() { return interruption.load(); }
void clearInterruption() { interruption.store(0); }
void checkInterruption() {
    if (const int sig = interruption.load())
        throw InterruptedError("interrupted by signal " + std::to_string(sig));
}

}  // namespace armsim
