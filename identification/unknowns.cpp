#include "identification/unknowns.h"

#include "basics/bound.h"

#include <algorithm>
#include <cmath>

namespace armsim {

namespace {

struct Info {
    ParameterId id;
    const char* name;
    const char* unit;
};
constexpr Info kInfo[] = {{ParameterId::Mass, "mass", "kg"},
                          {ParameterId::OptimalTendonLength, "optimal_tendon_length", "m"},
                          {ParameterId::OptimalFascicleLength, "optimal_fascicle_length", "m"},
                          {ParameterId::SlowFraction, "slow_fraction", "1"},
                          {ParameterId::MaxPathLength, "max_path_length", "m"}};

const Info& info(ParameterId id) {
    for (const Info& i : kInfo)
        if (i.id == id) return i;
    throw std::logic_error("unknown ParameterId");
}

}  // namespace

std::string getParameterName(ParameterId id) { return info(id).name; }
std::string getParameterUnit(ParameterId id) { return info(id).unit; }

ParameterId parseParameterName(const std::string& name) {
    std::string all;
    for (const Info& i : kInfo) {
        if (name == i.name) return i.id;
        all += std::string(all.empty() ? "" : ", ") + i.name;
    }
    throw InputError("unknown parameter '" + name + "': expected one of " + all);
}

Unknown makeUnknown(ParameterId id) {
    Unknown u;
    u.id = id;
    switch (id) {
        case ParameterId::Mass:
            u.lower = 0.05, u.upper = 1.0, u.tolerance = 1e-6;
            u.gain = 5e-4, u.gainMin = 1e-5, u.gainMax = 2e-4;
            break;
        case ParameterId::OptimalTendonLength:
            u.lower = 0.10, u.upper = 0.35, u.tolerance = 1e-5;
            u.gain = -1e-4, u.gainMin = 1e-4, u.gainMax = 2e-3;
            break;
        case ParameterId::OptimalFascicleLength:
            u.lower = 0.08, u.upper = 0.25, u.tolerance = 1e-5;
            break;
        case ParameterId::SlowFraction:
            u.lower = 0.05, u.upper = 0.95, u.tolerance = 1e-5;
            break;
        case ParameterId::MaxPathLength:
            u.lower = 0.35, u.upper = 0.50, u.tolerance = 1e-5;
            break;
    }
    return u;
}

std::vector<Unknown> makeDefaultUnknowns() {
    return {makeUnknown(ParameterId::Mass), makeUnknown(ParameterId::OptimalTendonLength)};
}

double getParameter(const MuscleParameters& p, ParameterId id) {
    switch (id) {
        case ParameterId::Mass: return p.mass;
        case ParameterId::OptimalTendonLength: return p.optimalTendonLength;
        case ParameterId::OptimalFascicleLength: return p.optimalFascicleLength;
        case ParameterId::SlowFraction: return p.slowFraction;
        case ParameterId::MaxPathLength: return p.maxPathLength;
    }
    throw std::logic_error("unknown ParameterId");
}

void setParameter(MuscleParameters& p, ParameterId id, double v) {
    switch (id) {
        case ParameterId::Mass: p.mass = v; return;
        case ParameterId::OptimalTendonLength: p.optimalTendonLength = v; return;
        case ParameterId::OptimalFascicleLength: p.optimalFascicleLength = v; return;
        case ParameterId::SlowFraction: p.slowFraction = v; return;
        case ParameterId::MaxPathLength: p.maxPathLength = v; return;
    }
    throw std::logic_error("unknown ParameterId");
}

ParameterMap::ParameterMap(MuscleParameters base, std::vector<Unknown> unknowns)
    : base_(std::move(base)), unknowns_(std::move(unknowns)) {
    if (unknowns_.empty()) throw InputError("unknowns: expected at least one parameter to identify");
    for (std::size_t i = 0; i < unknowns_.size(); ++i) {
        Unknown& u = unknowns_[i];
        const std::string f = "unknowns." + getParameterName(u.id) + ".";
        for (std::size_t j = 0; j < i; ++j)
            if (unknowns_[j].id == u.id)
                throw FieldError(f + "id", "parameter '" + getParameterName(u.id) + "' listed twice");
        const char* unit = info(u.id).unit;
        checkField(f + "lower", u.lower, Bound::any(unit));
        checkField(f + "upper", u.upper, {u.lower, 1e300, true, false, unit});
        if (std::isnan(u.start)) u.start = getParameter(base_, u.id);
        checkField(f + "start", u.start, Bound::closed(u.lower, u.upper, unit));
        if (std::isnan(u.scale)) u.scale = u.start != 0 ? std::abs(u.start) : u.upper - u.lower;
        checkField(f + "scale", u.scale, Bound::positive(unit));
        checkField(f + "tolerance", u.tolerance, Bound::positive(unit));
        if (!std::isnan(u.gain)) checkField(f + "gain", u.gain, Bound::any());
        checkField(f + "gain_min", u.gainMin, Bound::nonNegative());
        if (!(u.gainMax >= u.gainMin))
            throw FieldError(f + "gain_max", f + "gain_max = " + std::to_string(u.gainMax) +
                                                 ": expected >= gain_min = " + std::to_string(u.gainMin));
    }
}

MuscleParameters ParameterMap::toMuscle(const std::vector<double>& x) const {
    MuscleParameters p = base_;
    for (int i = 0; i < size(); ++i) setParameter(p, unknowns_[i].id, x[i]);
    return p;
}

std::vector<double> ParameterMap::fromMuscle(const MuscleParameters& p) const {
    std::vector<double> x;
    for (const Unknown& u : unknowns_) x.push_back(getParameter(p, u.id));
    return x;
}

namespace {
std::vector<double> collect(const std::vector<Unknown>& unknowns, double Unknown::*field) {
    std::vector<double> v;
    for (const Unknown& u : unknowns) v.push_back(u.*field);
    return v;
}
}  // namespace

std::vector<double> ParameterMap::getStart() const { return collect(unknowns_, &Unknown::start); }
std::vector<double> ParameterMap::getLower() const { return collect(unknowns_, &Unknown::lower); }
std::vector<double> ParameterMap::getUpper() const { return collect(unknowns_, &Unknown::upper); }
std::vector<double> ParameterMap::getScale() const { return collect(unknowns_, &Unknown::scale); }

std::vector<double> ParameterMap::toScaled(const std::vector<double>& x) const {
    std::vector<double> z(x.size());
    for (int i = 0; i < size(); ++i) z[i] = x[i] / unknowns_[i].scale;
    return z;
}

std::vector<double> ParameterMap::fromScaled(const std::vector<double>& z) const {
    std::vector<double> x(z.size());
    for (int i = 0; i < size(); ++i) x[i] = z[i] * unknowns_[i].scale;
    return x;
}

std::vector<double> ParameterMap::project(std::vector<double> x) const {
    for (int i = 0; i < size(); ++i) x[i] = std::clamp(x[i], unknowns_[i].lower, unknowns_[i].upper);
    return x;
}

std::vector<std::string> ParameterMap::getNames() const {
    std::vector<std::string> n;
    for (const Unknown& u : unknowns_) n.push_back(getParameterName(u.id));
    return n;
}

}  // namespace armsim
