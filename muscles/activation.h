// Neural activation inputs U(t) for the muscle: constant, step, ramp, or a sampled trace.
// Framework-free; the Simbody adapter evaluates it at the state's time.
#pragma once

#include <string>
#include <vector>

namespace armsim {

/// U(t), piecewise linear through the points (t_k, U_k), constant before the first and after the
/// last point. Two points at the same time make a step (U takes the later value from that time on).
/// Values are in [0, 1]; times in s, nondecreasing.
class ActivationProfile {
public:
    /// U = 0 for all t.
    ActivationProfile();
    /// Points must have equal length, nondecreasing times, values in [0, 1]; throws InputError
    /// naming what (e.g. "activation trace") and the offending index.
    ActivationProfile(std::vector<double> times, std::vector<double> values,
                      const std::string& what = "activation profile");

    static ActivationProfile constant(double U);
    /// U0 before t0, U1 from t0 on.
    static ActivationProfile step(double t0, double U0, double U1);
    /// U0 before t0, linear to U1 at t1, U1 after.
    static ActivationProfile ramp(double t0, double t1, double U0, double U1);
    /// Rest at 0 until tOn, rise to level over riseTime (0: a step), hold until tOff, fall to 0
    /// over riseTime.
    static ActivationProfile pulse(double tOn, double riseTime, double level, double tOff);

    double getValue(double t) const;
    /// Times where U or its slope changes: an integrator should restart there.
    const std::vector<double>& getBreakpoints() const { return times_; }
    const std::vector<double>& getValues() const { return values_; }
    /// Times where a sloped stretch of U(t) passes one of the levels, each the first double at which U
    /// is on the far side of its level (so U(t) there is already past it). Sorted, one per passing.
    std::vector<double> findCrossings(const std::vector<double>& levels) const;
    double getMaxValue() const;

private:
    std::vector<double> times_, values_;
};

/// Reads a sampled activation trace from a CSV file with columns time_s and activation (other
/// columns are ignored). Errors name the file, the line and the value.
ActivationProfile loadActivationTrace(const std::string& csvPath);

}  // namespace armsim
