// The unknowns of an identification: which muscle parameters are free, their bounds, start values,
// scales and learning-gain defaults, and the mapping parameter vector <-> MuscleParameters.
#pragma once

#include "basics/numbers.h"

#include "muscles/virtual_muscle.h"

#include <string>
#include <vector>

namespace armsim {

/// A muscle parameter that can be identified.
enum class ParameterId {
    Mass,                    ///< M, wet belly mass [kg]
    OptimalTendonLength,     ///< L0T [m]
    OptimalFascicleLength,   ///< L0 [m]
    SlowFraction,            ///< F_slow [1]
    MaxPathLength            ///< P_max [m]
};

/// One free parameter. Defaults (makeUnknown) are physiologically sensible ranges for a human elbow
/// flexor; every field can be overridden.
///
/// | id                      | name                    | bounds          | gain (ILC)  | gain bounds      |
/// |-------------------------|-------------------------|-----------------|-------------|------------------|
/// | Mass                    | mass                    | 0.05..1.0 kg    | 5e-4 kg/N   | 1e-5..2e-4 kg/N  |
/// | OptimalTendonLength     | optimal_tendon_length   | 0.10..0.35 m    | -1e-4 m/N   | 1e-4..2e-3 m/N   |
/// | OptimalFascicleLength   | optimal_fascicle_length | 0.08..0.25 m    | none        | none             |
/// | SlowFraction            | slow_fraction           | 0.05..0.95      | none        | none             |
/// | MaxPathLength           | max_path_length         | 0.35..0.50 m    | none        | none             |
///
/// Bounds: biceps heads weigh 0.1..0.5 kg with L0 0.1..0.22 m and L0T 0.15..0.3 m (thesis Table 4.2
/// after Li & Tong 2005; Murray et al. 2000); the bounds leave a margin either side. The ILC gains
/// are the thesis's (7.1: 0.5 g/N for M; 7.2.1: -0.01 cm/N for L0T, negative because the force falls
/// with L0T at 40 cm) and its gain-magnitude bounds 0.01 < |g| < 0.2 in g/N and cm/N (7.2.3).
struct Unknown {
    ParameterId id = ParameterId::Mass;
    double lower = 0;           ///< lower bound [unit]
    double upper = 0;           ///< upper bound [unit]
    double start = kNaN;   ///< start value [unit]; NaN: the base muscle's value
    double scale = kNaN;   ///< solver scale [unit] (inside solvers x / scale is order 1); NaN: |start|
    double tolerance = 0;       ///< resolution [unit]: false-position bracket width, smallest useful step
    double gain = kNaN;    ///< ILC learning gain [unit/N] (ilc-standard, ilc-constant); NaN: none
    double gainMin = 0;         ///< smallest |gain element| [unit/N] (bounded ILC variants)
    double gainMax = 1.0 / 0.0; ///< largest |gain element| [unit/N] (bounded ILC variants)
};

/// Snake-case name ("mass", "optimal_tendon_length", ...).
std::string getParameterName(ParameterId id);
/// SI unit ("kg", "m", "1").
std::string getParameterUnit(ParameterId id);
/// Parses a name from getParameterName; InputError listing the names otherwise.
ParameterId parseParameterName(const std::string& name);
/// The defaults of the table above.
Unknown makeUnknown(ParameterId id);
/// Mass and optimal tendon length with their defaults (the thesis's two unknowns).
std::vector<Unknown> makeDefaultUnknowns();
/// The parameter's value in a muscle.
double getParameter(const MuscleParameters& p, ParameterId id);
/// Sets the parameter's value in a muscle.
void setParameter(MuscleParameters& p, ParameterId id, double value);

/// Parameter vector x (physical units, one entry per unknown) <-> MuscleParameters, and the scaled
/// vector z = x / scale used inside solvers. Resolves NaN starts and scales from the base muscle and
/// validates bounds (FieldError "unknowns.<name>.<field>").
class ParameterMap {
public:
    ParameterMap(MuscleParameters base, std::vector<Unknown> unknowns);

    int size() const { return int(unknowns_.size()); }
    const std::vector<Unknown>& getUnknowns() const { return unknowns_; }
    const MuscleParameters& getBase() const { return base_; }
    /// The base muscle with x written in.
    MuscleParameters toMuscle(const std::vector<double>& x) const;
    /// The unknowns' values in a muscle.
    std::vector<double> fromMuscle(const MuscleParameters& p) const;
    std::vector<double> getStart() const;
    std::vector<double> getLower() const;
    std::vector<double> getUpper() const;
    std::vector<double> getScale() const;
    std::vector<double> toScaled(const std::vector<double>& x) const;
    std::vector<double> fromScaled(const std::vector<double>& z) const;
    /// x clipped into the bounds.
    std::vector<double> project(std::vector<double> x) const;
    std::vector<std::string> getNames() const;

private:
    MuscleParameters base_;
    std::vector<Unknown> unknowns_;
};

}  // namespace armsim
