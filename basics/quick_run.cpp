#include "basics/quick_run.h"

#include "basics/errors.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <set>

namespace armsim {

bool isQuickRun() {
    const char* v = std::getenv("ARMSIM_QUICK");
    if (!v || !*v || std::string(v) == "0") return false;
    if (std::string(v) == "1") return true;
    throw InputError(std::string("environment variable ARMSIM_QUICK=") + v + ": expected 1 (try quickly) or 0");
}

int capForQuickRun(int value, int cap, const std::string& what) {
    if (!isQuickRun() || value <= cap) return value;   // a bad ARMSIM_QUICK is refused whatever the size
    static std::mutex mutex;
    static std::set<std::string> said;
    std::lock_guard<std::mutex> lock(mutex);
    if (said.insert(what).second)
        std::fprintf(stderr, "ARMSIM_QUICK=1: %s %d capped at %d (a quick try, not a result)\n", what.c_str(), value, cap);
    return std::min(value, cap);
}

}  // namespace armsim
