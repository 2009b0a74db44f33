#include "basics/errors.h"

#include <atomic>
#include <cstdlib>

namespace armsim {

namespace {
std::atomic<int> interruption{0};
}

FieldError::FieldError(std::string field, const std::string& message)
    // A command-line option ("--noise") is named as typed, not as a file's field.
    : InputError(field.rfind("--", 0) == 0 ? field + " " + message : "field " + describeField(field) + " " + message),
      field_(std::move(field)), detail_(message) {}

std::string describeField(const std::string& path) {
    // Indices inside the path become 1-based; the last list entry is said in words after the key.
    std::string out;
    std::size_t lastIndex = std::string::npos, lastEnd = 0;
    long lastNumber = 0;
    for (std::size_t i = 0; i < path.size(); ++i) {
        if (path[i] == '[') {
            const std::size_t close = path.find(']', i);
            if (close == std::string::npos) break;
            char* end = nullptr;
            const long k = std::strtol(path.c_str() + i + 1, &end, 10);
            if (end != path.c_str() + close) break;
            lastIndex = i;
            lastEnd = close + 1;
            lastNumber = k;
        }
    }
    if (lastIndex == std::string::npos) return "'" + path + "'";
    auto oneBased = [](const std::string& s) {   // earlier indices: [k] -> [k + 1]
        std::string r;
        for (std::size_t i = 0; i < s.size(); ++i) {
            const std::size_t close = s[i] == '[' ? s.find(']', i) : std::string::npos;
            char* end = nullptr;
            const long k = close != std::string::npos ? std::strtol(s.c_str() + i + 1, &end, 10) : 0;
            if (close != std::string::npos && end == s.c_str() + close) {
                r += "[" + std::to_string(k + 1) + "]";
                i = close;
            } else {
                r += s[i];
            }
        }
        return r;
    };
    const std::string list = oneBased(path.substr(0, lastIndex));
    std::string rest = path.substr(lastEnd);
    if (!rest.empty() && rest[0] == '.') rest = rest.substr(1);
    const std::string entry = "entry " + std::to_string(lastNumber + 1);
    if (rest.empty()) return "'" + list + "' (" + entry + ")";
    return "'" + oneBased(rest) + "' (" + list + ", " + entry + ")";
}

void requestInterruption(int sig) { interruption.store(sig); }
int getInterruption() { return interruption.load(); }
void clearInterruption() { interruption.store(0); }
void checkInterruption() {
    if (const int sig = interruption.load())
        throw InterruptedError("interrupted by signal " + std::to_string(sig));
}

}  // namespace armsim
