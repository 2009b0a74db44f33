#include "basics/format.h"

#include <fmt/format.h>

namespace armsim {

// Out of line: libfmt's templates instantiated in a translation unit that has `using namespace SimTK`
// meet SimTK's operator templates (an ambiguous, non-constexpr comparison).
std::string formatNumber(double v, int significantDigits) { return fmt::format("{:.{}g}", v, significantDigits); }

}  // namespace armsim
