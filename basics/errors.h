// The error types every armsim library throws, and the process-wide interruption flag long loops poll.
// Framework-free.
#pragma once

#include <stdexcept>
#include <string>

namespace armsim {

/// A user error (bad file, bad value, bad option). The CLI prints what() and exits non-zero. Messages
/// name the file, line or field, the offending value and what was expected, e.g.
///   "assets/muscles/biceps.yaml:4: field 'mass' = -0.3: expected > 0 (kg)".
class InputError : public std::invalid_argument {
public:
    using std::invalid_argument::invalid_argument;
};

/// A simulation that cannot go on (NaN in a state, a fascicle beyond the model's validity bound,
/// an integrator failure). The message names the simulated time and the element.
class SimulationError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A run stopped because the user asked (SIGINT or SIGTERM, see requestInterruption); the work in
/// progress was abandoned and its partial output removed by the writers' destructors.
class InterruptedError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A value that violates a documented bound. field is the dotted parameter name ("slow.Tf1"), so a
/// loader can add the file and line where that field was written (ParamNode::rethrowWithLocation).
class FieldError : public InputError {
public:
    FieldError(std::string field, const std::string& message);
    const std::string& getField() const { return field_; }
    const std::string& getDetail() const { return detail_; }
private:
    std::string field_;
    std::string detail_;
};

/// A field path as a message names it: "a.b" as 'a.b'; a list entry by its key and 1-based place, so
/// "conditions[1].flexion_deg" is 'flexion_deg' (conditions, entry 2) and "angles[0]" is 'angles' (entry 1).
std::string describeField(const std::string& path);

/// Records that signal `sig` asked the process to stop (async-signal-safe: sets an atomic).
void requestInterruption(int sig);
/// The signal that asked to stop, 0 if none.
int getInterruption();
/// Forgets a request (a library host such as Python that goes on after a stop).
void clearInterruption();
/// Throws InterruptedError when an interruption was requested; long loops call it between tasks
/// (runParallel does before every task).
void checkInterruption();

}  // namespace armsim
