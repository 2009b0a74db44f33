// The protocol kinds' table: each kind's name, reader, fits and writer (experiments/protocol_run.h).
#include "basics/errors.h"
#include "experiments/protocol_run.h"

namespace armsim {

namespace detail {

const std::vector<ProtocolKindSpec>& getProtocolKindSpecs() {
    static const std::vector<ProtocolKindSpec> kinds = {
        {ProtocolKind::Mvc, "mvc", true, false, readMvcConditions, fitMvc, writeMvcFiles},
        {ProtocolKind::Submaximal, "submaximal", true, true, readSubmaximalConditions, fitSubmaximal, writeSubmaximalFiles},
        {ProtocolKind::ForceLength, "force_length", true, false, readForceLengthConditions, fitForceLength,
         writeForceLengthFiles},
        {ProtocolKind::Composition, "composition", false, false, readCompositionConditions, nullptr, writeCompositionFiles},
    };
    return kinds;
}

const ProtocolKindSpec& getProtocolKindSpec(ProtocolKind kind) {
    for (const ProtocolKindSpec& k : getProtocolKindSpecs())
        if (k.kind == kind) return k;
    throw std::logic_error("protocol kind " + std::to_string(int(kind)) + " has no row in getProtocolKindSpecs");
}

}  // namespace detail

std::string getProtocolKindName(ProtocolKind kind) { return detail::getProtocolKindSpec(kind).name; }

}  // namespace armsim
