#include "muscles/activation.h"

#include "basics/bound.h"
#include "basics/format.h"
#include "basics/table.h"

#include <algorithm>
#include <cmath>

namespace armsim {

ActivationProfile::ActivationProfile() : times_{0.0}, values_{0.0} {}

ActivationProfile::ActivationProfile(std::vector<double> times, std::vector<double> values,
                                     const std::string& what)
    : times_(std::move(times)), values_(std::move(values)) {
    if (times_.empty() || times_.size() != values_.size())
        throw InputError(what + ": expected as many times as values and at least one point (got " +
                         std::to_string(times_.size()) + " times, " + std::to_string(values_.size()) +
                         " values)");
    for (std::size_t k = 0; k < times_.size(); ++k) {
        const std::string at = what + " point " + std::to_string(k);
        if (!std::isfinite(times_[k])) throw InputError(at + ": time is not finite");
        if (k > 0 && times_[k] < times_[k - 1])
            throw InputError(at + ": time " + std::to_string(times_[k]) + " s is before the previous " +
                             std::to_string(times_[k - 1]) + " s: expected nondecreasing times");
        checkField(at + " activation", values_[k], Bound::closed(0, 1));
    }
}

ActivationProfile ActivationProfile::constant(double U) { return ActivationProfile({0.0}, {U}); }

ActivationProfile ActivationProfile::step(double t0, double U0, double U1) {
    return ActivationProfile({t0, t0}, {U0, U1}, "step activation");
}

ActivationProfile ActivationProfile::ramp(double t0, double t1, double U0, double U1) {
    if (!(t1 > t0)) throw InputError("ramp activation: end time must be after start time");
    return ActivationProfile({t0, t1}, {U0, U1}, "ramp activation");
}

ActivationProfile ActivationProfile::pulse(double tOn, double riseTime, double level, double tOff) {
    checkField("rise time", riseTime, Bound::nonNegative("s"));
    if (!(tOff >= tOn + riseTime))
        throw InputError("activation pulse: off time " + std::to_string(tOff) +
                         " s must come after the rise ends at " + std::to_string(tOn + riseTime) + " s");
    return ActivationProfile({tOn, tOn + riseTime, tOff, tOff + riseTime}, {0.0, level, level, 0.0},
                             "activation pulse");
}

std::vector<double> ActivationProfile::findCrossings(const std::vector<double>& levels) const {
    std::vector<double> crossings;
    for (std::size_t k = 1; k < times_.size(); ++k) {
        const double t0 = times_[k - 1], t1 = times_[k], U0 = values_[k - 1], U1 = values_[k];
        if (!(t1 > t0) || U0 == U1) continue;
        for (double level : levels) {
            // Passed when U goes from one side of the level (U < level counts as below) to the other.
            const bool rising = U1 > U0;
            if (rising ? !(U0 < level && level <= U1) : !(U1 < level && level <= U0)) continue;
            double t = t0 + (level - U0) / (U1 - U0) * (t1 - t0);
            auto past = [&](double tt) { return rising ? getValue(tt) >= level : getValue(tt) < level; };
            while (t < t1 && !past(t)) t = std::nextafter(t, t1);
            crossings.push_back(t);
        }
    }
    std::sort(crossings.begin(), crossings.end());
    return crossings;
}

double ActivationProfile::getValue(double t) const {
    // First point with time > t; U is right-continuous at steps.
    const auto it = std::upper_bound(times_.begin(), times_.end(), t);
    if (it == times_.begin()) return values_.front();
    if (it == times_.end()) return values_.back();
    const std::size_t k = std::size_t(it - times_.begin());
    const double t0 = times_[k - 1], t1 = times_[k];
    const double w = (t - t0) / (t1 - t0);
    return values_[k - 1] + w * (values_[k] - values_[k - 1]);
}

double ActivationProfile::getMaxValue() const { return *std::max_element(values_.begin(), values_.end()); }

ActivationProfile loadActivationTrace(const std::string& csvPath) {
    const Table t = Table::readCsv(csvPath);
    for (const char* c : {"time_s", "activation"})
        if (!t.hasColumn(c))
            throw InputError(csvPath + ": no column '" + c + "' (expected columns time_s,activation)");
    if (t.getNumRows() == 0) throw InputError(csvPath + ": no data rows");
    const std::vector<double> time = t.getColumn("time_s"), U = t.getColumn("activation");
    for (int i = 0; i < t.getNumRows(); ++i) {
        const std::string at = csvPath + ":" + std::to_string(t.getSourceLine(i));
        if (!std::isfinite(time[i])) throw InputError(at + ": column 'time_s' = " + formatNumber(time[i]) + ": expected a finite time");
        if (!(U[i] >= 0 && U[i] <= 1))
            throw InputError(at + ": column 'activation' = " + formatNumber(U[i]) + ": expected in [0, 1]");
        if (i > 0 && !(time[i] >= time[i - 1]))
            throw InputError(at + ": column 'time_s' = " + formatNumber(time[i]) + " is before the previous row's " +
                             formatNumber(time[i - 1]) + ": expected nondecreasing times");
    }
    // A trial starts at 0: a trace starting later would have its first value held back to 0 unseen.
    if (time.front() > 0)
        throw InputError(csvPath + ":" + std::to_string(t.getSourceLine(0)) + ": column 'time_s' = " + formatNumber(time.front()) +
                         ": expected the trace to start at 0 s (or before), where the trial starts");
    return ActivationProfile(time, U, csvPath);
}

}  // namespace armsim
