#include "identification/faithful_model.h"

#include "basics/bound.h"
#include "basics/format.h"
#include "model/geometry.h"
#include "model/trial.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace armsim {

namespace {

constexpr double kPathMatchTol = 1e-6;    // m: an observation's path vs the arm's P(its angle)
constexpr double kAngleRangeTol = 1e-9;   // deg: slack at the ends of the elbow range
constexpr double kCosineSlack = 1e-12;    // rounding slack of the law of cosines at 0 and 180 deg

constexpr std::pair<ForceEstimate, const char*> kEstimates[] = {
    {ForceEstimate::MomentArm, "moment-arm"}, {ForceEstimate::FixedRatio, "fixed-ratio"}, {ForceEstimate::TrueForce, "true"}};

}  // namespace

std::string getForceEstimateName(ForceEstimate e) {
    for (const auto& [id, name] : kEstimates)
        if (id == e) return name;
    throw std::logic_error("unknown ForceEstimate");
}

ForceEstimate parseForceEstimateName(const std::string& name) {
    std::string all;
    for (const auto& [id, n] : kEstimates) {
        if (name == n) return id;
        all += std::string(all.empty() ? "" : ", ") + n;
    }
    throw InputError("force estimate '" + name + "': expected one of " + all);
}

void FaithfulProtocol::validate() const {
    checkField("protocol.rest", restDuration, Bound::positive("s"));
    checkField("protocol.hold", holdDuration, Bound::positive("s"));
    checkField("protocol.averaging_window", averagingWindow, {0, holdDuration, true, false, "s, within the hold"});
    checkField("protocol.sample_rate", sampleRate, Bound::positive("Hz"));
    checkField("protocol.accuracy", accuracy, Bound::open(0, 1));
    // The window must hold samples: at least two, or its mean is one sample's luck.
    checkField("protocol.averaging_window", averagingWindow * sampleRate,
               Bound::closed(2, 1e300, "samples in the window: window x sample rate"));
    calcNumSamples(restDuration + holdDuration, sampleRate);
}

FaithfulProtocol FaithfulProtocol::makeReference() {
    FaithfulProtocol p;
    p.sampleRate = 1000.0;
    return p;
}

double calcElbowAngleFromPath(double A, double B, double path) {
    double c = (A * A + B * B - path * path) / (2 * A * B);
    if (c < -1 - kCosineSlack || c > 1 + kCosineSlack || !std::isfinite(c)) return std::numeric_limits<double>::quiet_NaN();
    c = std::clamp(c, -1.0, 1.0);
    return std::acos(c);
}

FaithfulForceModel::FaithfulForceModel(ArmParameters arm, FaithfulModelOptions options)
    : arm_(std::move(arm)), options_(std::move(options)) {
    arm_.validate();
    setup_ = ArmSetup::loadDefault();
    setup_.arm = arm_;
    setup_.muscles[setup_.primary].maxPathFromRange = false;
    options_.protocol.validate();
    checkField("jobs", options_.jobs, Bound::closed(1, 256));
}

std::vector<double> FaithfulForceModel::calcElbowAngles(const ObservationSet& set) const {
    const double A = arm_.originDistance, B = arm_.insertionDistance;
    const double lo = arm_.minElbowAngleDeg, hi = arm_.maxElbowAngleDeg;
    const double pLo = calcBicepsPathLength(A, B, degToRad(lo)), pHi = calcBicepsPathLength(A, B, degToRad(hi));
    const std::string range = "the arm's elbow range " + formatNumber(lo, 8) + ".." + formatNumber(hi, 8) + " deg (paths " + formatNumber(pLo, 8) + ".." +
                              formatNumber(pHi, 8) + " m for A = " + formatNumber(A, 8) + " m, B = " + formatNumber(B, 8) + " m)";
    std::vector<double> angles;
    for (int i = 0; i < int(set.points.size()); ++i) {
        const Observation& o = set.points[i];
        double theta = o.angle;
        if (std::isfinite(theta)) {
            const double p = calcBicepsPathLength(A, B, theta);
            if (!(std::abs(p - o.pathLength) <= kPathMatchTol))
                throw InputError(set.where(i) + ": angle " + formatNumber(radToDeg(theta), 8) + " deg with path " +
                                 formatNumber(o.pathLength, 8) + " m, but the arm's geometry gives " + formatNumber(p, 8) +
                                 " m there: expected the path of the arm's biceps (convert angles with "
                                 "the arm's A and B)");
        } else {
            theta = calcElbowAngleFromPath(A, B, o.pathLength);
        }
        const double deg = radToDeg(theta);
        if (!(deg >= lo - kAngleRangeTol && deg <= hi + kAngleRangeTol))
            throw InputError(set.where(i) + ": path " + formatNumber(o.pathLength, 8) + " m" +
                             (std::isfinite(theta) ? " (elbow angle " + formatNumber(deg, 8) + " deg)" : "") +
                             " is outside " + range + ": expected a path the arm can take");
        angles.push_back(std::clamp(theta, degToRad(lo), degToRad(hi)));
    }
    return angles;
}

std::vector<double> FaithfulForceModel::calcForces(const MuscleParameters& params,
                                                   const std::vector<Observation>& observations) const {
    ObservationSet set;
    set.source = "faithful-model observations";
    set.points = observations;
    const std::vector<double> angles = calcElbowAngles(set);

    ArmSetup setup = setup_;
    setup.biceps() = params;
    const FaithfulProtocol& p = options_.protocol;
    std::vector<IsometricTrialSettings> trials;
    for (std::size_t k = 0; k < observations.size(); ++k) {
        IsometricTrialSettings s;
        s.elbowAngle = angles[k];
        s.activation = observations[k].activation;
        s.restDuration = p.restDuration;
        s.holdDuration = p.holdDuration;
        s.averagingWindow = p.averagingWindow;
        s.sampleRate = p.sampleRate;
        s.integration.accuracy = p.accuracy;
        trials.push_back(s);
    }
    const std::vector<IsometricTrialResult> results = runIsometricTrials(setup, trials, options_.jobs);
    trials_ += long(results.size());
    std::vector<double> forces;
    for (const IsometricTrialResult& r : results) {
        const IsometricSummary& s = r.summary;
        if (s.saturated) ++saturated_;
        switch (options_.estimate) {
            case ForceEstimate::MomentArm: forces.push_back(s.meanForceMomentArm); break;
            case ForceEstimate::FixedRatio: forces.push_back(s.meanForceFixedRatio); break;
            case ForceEstimate::TrueForce: forces.push_back(s.meanForce); break;
        }
    }
    return forces;
}

std::string FaithfulForceModel::describe() const {
    const FaithfulProtocol& p = options_.protocol;
    return "faithful model (" + getForceEstimateName(options_.estimate) + " estimate, " + formatNumber(p.holdDuration, 8) +
           " s hold, mean of the last " + formatNumber(p.averagingWindow, 8) + " s, " + formatNumber(p.sampleRate, 8) + " Hz, accuracy " +
           formatNumber(p.accuracy, 8) + ")";
}

}  // namespace armsim
