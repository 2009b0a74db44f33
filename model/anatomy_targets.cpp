#include "model/anatomy_targets.h"

#include "basics/bound.h"
#include "basics/errors.h"
#include "basics/format.h"
#include "basics/param_node.h"
#include "model/mvc_curve.h"
#include "muscles/muscle_file.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace armsim {

namespace {

const std::vector<std::string> kKindNames = {"moment_arm", "mvc", "volume", "share", "optimum_angle", "forearm_mvc",
                                             "posture_ratio"};

// Band units per kind: the file's unit, SI's, and the factor between them.
struct Unit {
    const char* file;
    const char* si;
    double toSi;
};
const Unit kUnits[] = {{"mm", "m", 1e-3}, {"N m", "N m", 1}, {"cm^3", "m^3", 1e-6}, {"1", "1", 1},
                       {"deg", "deg", 1},  {"N m", "N m", 1}, {"1", "1", 1}};

// Slips of unit the bands' bounds let through: a moment arm band in m (within 1 mm), a volume in m^3
// (under 1 cm^3: no arm muscle is that small), an optimum angle in radians. (The bounds of an MVC, at
// most 300 N m about the elbow and 100 N m about the forearm, twice the strongest measured, keep N cm
// out.)
void checkTargetUnits(const ParamNode& n, const AnatomyTarget& t, const Unit& u) {
    const double lo = t.lower / u.toSi, hi = t.upper / u.toSi;
    auto refuse = [&](const std::string& why) {
        throw InputError(n.where("lower") + ": the band [" + formatNumber(lo) + ", " + formatNumber(hi) + "] " + u.file + ": " + why);
    };
    if (t.kind == TargetKind::MomentArm && std::abs(lo) < 1 && std::abs(hi) < 1)
        refuse("within 1 mm: expected mm (a band in m, say 0.042 for 42 mm, would read as 0.042 mm)");
    if (t.kind == TargetKind::Volume && hi < 1)
        refuse("under 1 cm^3, smaller than any arm muscle: expected cm^3 (a volume in m^3 or L would read this small)");
    if (t.kind == TargetKind::OptimumAngle) {
        try {
            checkDegreesNotRadians("lower", {lo, hi});
        } catch (const FieldError& e) {
            refuse(e.getDetail());
        }
    }
}

std::vector<int> findCovered(const std::vector<std::string>& muscles, const std::string& family) {
    std::vector<int> out;
    for (int i = 0; i < int(muscles.size()); ++i)
        if (doesFamilyCoverMuscle(family, muscles[i])) out.push_back(i);
    return out;
}

// An armsim model's curves on a geometry already computed.
AnatomyCurves makeAnatomyCurves(const ArmSetup& setup, const MvcGeometry& geometry) {
    AnatomyCurves c;
    for (const MuscleSpec& m : setup.muscles) {
        c.muscles.push_back(m.params.name);
        c.volume.push_back(m.params.mass / m.params.coefficients.density);
    }
    c.minFlexionDeg = setup.arm.getMinFlexionDeg();
    c.maxFlexionDeg = setup.arm.getMaxFlexionDeg();
    c.flexionDeg = geometry.flexionDeg;
    c.momentArm = geometry.momentArm;
    c.flexion = calcSteadyMvcCurve(setup.muscles, geometry, MuscleGroup::Flexor, setup.effort);
    c.extension = calcSteadyMvcCurve(setup.muscles, geometry, MuscleGroup::Extensor, setup.effort);
    c.full = calcSteadyMvcCurve(setup.muscles, geometry, MuscleGroup::Flexor, SubjectEffort{1, 0});
    return c;
}

// Flexion angle where the fibre length crosses 1 going along the samples (linear interpolation); NaN
// when it does not.
double findOptimumAngle(const SteadyMvcCurve& c, int m) {
    for (std::size_t a = 1; a < c.flexionDeg.size(); ++a) {
        const double l0 = c.points[a - 1][m].fibreLength - 1, l1 = c.points[a][m].fibreLength - 1;
        if (l0 == 0) return c.flexionDeg[a - 1];
        if ((l0 < 0) != (l1 < 0))
            return c.flexionDeg[a - 1] + (c.flexionDeg[a] - c.flexionDeg[a - 1]) * l0 / (l0 - l1);
    }
    return NAN;
}

// Where the fibre length would cross 1 beyond the range, from the slope over the last 10 deg at the end
// nearest to 1 (for a fit to steer by when there is no crossing), at most kMaxExtrapolationDeg beyond;
// NaN for a flat curve or one whose trend there points back into the range.
double extrapolateOptimumAngle(const SteadyMvcCurve& c, int m) {
    const std::size_t n = c.flexionDeg.size();
    if (n < 2) return NAN;
    const bool first = std::abs(c.points[0][m].fibreLength - 1) < std::abs(c.points[n - 1][m].fibreLength - 1);
    std::size_t a = first ? 0 : n - 1, b = a;
    while (std::abs(c.flexionDeg[b] - c.flexionDeg[a]) < 10 && (first ? b + 1 < n : b > 0)) b += first ? 1 : -1;
    const double slope = (c.points[b][m].fibreLength - c.points[a][m].fibreLength) / (c.flexionDeg[b] - c.flexionDeg[a]);
    if (!(std::abs(slope) > 0)) return NAN;
    constexpr double kMaxExtrapolationDeg = 90;
    const double beyond = (1 - c.points[a][m].fibreLength) / slope;   // deg from the end angle
    if (first ? beyond > 0 : beyond < 0) return NAN;                   // the trend crosses inside: not monotonic
    return c.flexionDeg[a] + std::clamp(beyond, -kMaxExtrapolationDeg, kMaxExtrapolationDeg);
}

// A forearm target the model can score: it rotates, and the target's posture is within its range.
bool isScoredForearmTarget(const ArmSetup& setup, const AnatomyTarget& t) {
    const ArmParameters::ForearmRotation& rot = setup.arm.forearmRotation;
    const bool forearm = t.kind == TargetKind::ForearmMvc || t.kind == TargetKind::PostureRatio;
    return forearm && rot.enabled && t.rotationDeg >= rot.minDeg && t.rotationDeg <= rot.maxDeg &&
           t.flexionDeg >= setup.arm.getMinFlexionDeg() && t.flexionDeg <= setup.arm.getMaxFlexionDeg();
}

}  // namespace

const char* getTargetKindName(TargetKind k) { return kKindNames[int(k)].c_str(); }
const char* getTargetFileUnit(TargetKind k) { return kUnits[int(k)].file; }
const char* getTargetSiUnit(TargetKind k) { return kUnits[int(k)].si; }
double getTargetFileToSi(TargetKind k) { return kUnits[int(k)].toSi; }

std::string describeTargetCondition(const AnatomyTarget& t) {
    switch (t.kind) {
    case TargetKind::Mvc: return t.direction == MuscleGroup::Flexor ? "flexion" : "extension";
    case TargetKind::ForearmMvc:
        return std::string(getEffortName(t.forearmEffort)) +
               " at rotation " + formatNumber(t.rotationDeg) + " deg";
    case TargetKind::PostureRatio: return "flexion at rotation " + formatNumber(t.rotationDeg) + " deg / neutral";
    default: return "";
    }
}

bool doesFamilyCoverMuscle(const std::string& family, const std::string& muscle) {
    return muscle.compare(0, family.size(), family) == 0;
}

namespace {
// The file's angles of one field, in degrees unless all look like radians (basics/bound.h), named at
// the first target whose angle is not whole.
void checkTargetAnglesInDegrees(const std::vector<AnatomyTarget>& targets, double AnatomyTarget::*field, const char* name) {
    std::vector<double> angles;
    const AnatomyTarget* fractional = nullptr;
    for (const AnatomyTarget& t : targets)
        if (std::isfinite(t.*field) && (name != std::string("rotation_deg") || t.kind == TargetKind::ForearmMvc ||
                                        t.kind == TargetKind::PostureRatio)) {
            angles.push_back(t.*field);
            if (!fractional && t.*field != std::round(t.*field)) fractional = &t;
        }
    if (!fractional) return;
    try {
        checkDegreesNotRadians(name, angles);
    } catch (const InputError& e) {
        throw InputError(fractional->where + ": " + e.what());
    }
}
}  // namespace

std::vector<AnatomyTarget> loadAnatomyTargets(const std::string& path) {
    const ParamNode root = ParamNode::loadFile(path);
    std::vector<AnatomyTarget> out;
    for (const ParamNode& n : root.children("targets")) {
        AnatomyTarget t;
        t.where = n.where();
        const std::string kind = n.getChoice("kind", kKindNames, "");
        t.kind = TargetKind(std::find(kKindNames.begin(), kKindNames.end(), kind) - kKindNames.begin());
        const Unit& u = kUnits[int(t.kind)];
        const bool forearm = t.kind == TargetKind::ForearmMvc || t.kind == TargetKind::PostureRatio;
        if (t.kind != TargetKind::Mvc && !forearm) t.muscle = n.getString("muscle");
        if (t.kind == TargetKind::ForearmMvc)
            t.forearmEffort = parseEffortName(n.getChoice("direction", {"supination", "pronation"}, ""));
        if (forearm) t.rotationDeg = n.getNumber("rotation_deg", Bound::closed(-120, 120, "deg"));
        if (t.kind == TargetKind::Mvc)
            t.direction = n.getChoice("direction", {"flexion", "extension"}, "") == "flexion" ? MuscleGroup::Flexor
                                                                                             : MuscleGroup::Extensor;
        if (t.kind == TargetKind::MomentArm || t.kind == TargetKind::Mvc || t.kind == TargetKind::Share || forearm)
            t.flexionDeg = n.getNumber("flexion_deg", Bound::closed(0, 180, "deg"));
        const Bound band = t.kind == TargetKind::Share ? Bound::closed(0, 1)
                           : t.kind == TargetKind::PostureRatio ? Bound::closed(0, 5)
                           : t.kind == TargetKind::ForearmMvc ? Bound::closed(0, 100, "N m")
                           : t.kind == TargetKind::OptimumAngle ? Bound::closed(0, 180, "deg")
                           : t.kind == TargetKind::MomentArm ? Bound::closed(-200, 200, "mm")
                           : t.kind == TargetKind::Mvc ? Bound::closed(0, 300, "N m")
                                                       : Bound::closed(0, 1e5, "cm^3");
        t.lower = n.getNumber("lower", band) * u.toSi;
        t.upper = n.getNumber("upper", band) * u.toSi;
        if (t.lower > t.upper)
            throw InputError(n.where("upper") + ": field 'upper' = " + formatNumber(t.upper / u.toSi) + " " +
                             u.file + ": expected >= lower = " + formatNumber(t.lower / u.toSi) + " " + u.file);
        checkTargetUnits(n, t, u);
        // A tolerance over a quarter of the quantity's whole range would pass any model (1000 mm on a
        // moment arm): a unit slip, not a band.
        t.tolerance = n.getNumber("tolerance", Bound::closed(0, (band.hi - band.lo) / 4, band.unit), 0.0) * u.toSi;
        if (t.lower == t.upper && t.tolerance == 0)
            throw InputError(n.where("upper") + ": a point value (lower = upper = " + formatNumber(t.upper / u.toSi) +
                             " " + u.file + ") needs a tolerance > 0: expected a band or a tolerance");
        t.weight = n.getNumber("weight", Bound::closed(0, 1e3), 1.0);
        t.source = n.getString("source");
        n.finish();
        out.push_back(t);
    }
    root.finish();
    if (out.empty()) throw InputError(root.where("targets") + ": field 'targets' is empty: expected at least one target");
    checkTargetAnglesInDegrees(out, &AnatomyTarget::flexionDeg, "flexion_deg");
    checkTargetAnglesInDegrees(out, &AnatomyTarget::rotationDeg, "rotation_deg");
    return out;
}

std::vector<AnatomyTarget> loadDefaultAnatomyTargets() {
    return loadAnatomyTargets(getAssetDirectory() + "/reference/elbow_targets.yaml");
}

std::vector<double> findAnatomyAngles(const std::vector<AnatomyTarget>& targets, double minDeg, double maxDeg) {
    std::vector<double> angles;
    const bool optimumAngles = std::any_of(targets.begin(), targets.end(),
                                           [](const AnatomyTarget& t) { return t.kind == TargetKind::OptimumAngle; });
    if (optimumAngles)
        for (double a = minDeg; a <= maxDeg + 1e-9; a += 1) angles.push_back(a);
    for (const AnatomyTarget& t : targets)
        if (std::isfinite(t.flexionDeg) && t.flexionDeg >= minDeg && t.flexionDeg <= maxDeg) angles.push_back(t.flexionDeg);
    std::sort(angles.begin(), angles.end());
    angles.erase(std::unique(angles.begin(), angles.end()), angles.end());
    return angles;
}

AnatomyCurves calcAnatomyCurves(const ArmSetup& setup, const std::vector<double>& flexionDeg) {
    return makeAnatomyCurves(setup, calcMvcGeometry(setup, flexionDeg));
}

// A moment-arm band on the other side of zero from the muscles it names (flexion positive): a flexor's
// band below zero, an extensor's above it, is a sign slip the scorecard would report as a model's miss.
void checkMomentArmSigns(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets) {
    std::vector<std::string> names;
    for (const MuscleSpec& m : setup.muscles) names.push_back(m.params.name);
    for (const AnatomyTarget& t : targets) {
        if (t.kind != TargetKind::MomentArm) continue;
        for (int m : findCovered(names, t.muscle)) {
            const MuscleGroup g = setup.muscles[std::size_t(m)].group;
            const bool wrong = (g == MuscleGroup::Flexor && t.upper < 0) || (g == MuscleGroup::Extensor && t.lower > 0);
            if (!wrong) continue;
            throw InputError(t.where + ": moment_arm of " + t.muscle + " at " + formatNumber(t.flexionDeg) + " deg: [" +
                             formatNumber(1000 * t.lower, 6) + ", " + formatNumber(1000 * t.upper, 6) + "] mm, but " + names[std::size_t(m)] +
                             " of model '" + setup.name + "' is " + (g == MuscleGroup::Flexor ? "a flexor" : "an extensor") +
                             ": expected " + (g == MuscleGroup::Flexor ? "> 0" : "< 0") +
                             " (elbow moment arms are positive in flexion)");
        }
    }
}

AnatomySweep calcAnatomySweep(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets) {
    checkMomentArmSigns(setup, targets);
    AnatomySweep sweep;
    sweep.flexionDeg = findAnatomyAngles(targets, setup.arm.getMinFlexionDeg(), setup.arm.getMaxFlexionDeg());
    sweep.geometry = calcMvcGeometry(setup, sweep.flexionDeg);

    std::set<double> forearmAngles, rotations;
    for (const AnatomyTarget& t : targets)
        if (isScoredForearmTarget(setup, t)) {
            forearmAngles.insert(t.flexionDeg);
            rotations.insert(t.rotationDeg);
            if (t.kind == TargetKind::PostureRatio) rotations.insert(0.0);
        }
    for (double r : rotations)
        sweep.byRotation[r] = calcMvcGeometry(setup, {forearmAngles.begin(), forearmAngles.end()}, r);
    return sweep;
}

std::vector<TargetScore> scoreAnatomy(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets) {
    return scoreAnatomy(setup, targets, calcAnatomySweep(setup, targets));
}

namespace {

// Appends the score of one target that the curves answer (not a forearm target).
void scoreCurveTarget(const AnatomyCurves& c, const AnatomyTarget& t, const std::vector<int>& sharedMuscles,
                      std::vector<TargetScore>& out) {
    auto add = [&](const std::string& muscle, double value, double fitValue = NAN) {
        TargetScore s;
        s.target = t;
        s.muscle = muscle;
        s.value = value;
        s.fitValue = std::isfinite(value) ? value : fitValue;
        s.pass = std::isfinite(value) && value >= t.lower - t.tolerance && value <= t.upper + t.tolerance;
        out.push_back(s);
    };
    auto indexOf = [&](double deg) {
        return int(std::lower_bound(c.flexionDeg.begin(), c.flexionDeg.end(), deg) - c.flexionDeg.begin());
    };
    if (t.kind == TargetKind::Mvc) {
        const SteadyMvcCurve& curve = t.direction == MuscleGroup::Flexor ? c.flexion : c.extension;
        return add("", std::abs(curve.totalTorque[indexOf(t.flexionDeg)]));
    }
    const std::vector<int> covered = findCovered(c.muscles, t.muscle);
    if (covered.empty()) return;
    switch (t.kind) {
    case TargetKind::MomentArm:
        for (int m : covered) add(c.muscles[m], c.momentArm[indexOf(t.flexionDeg)][m]);
        break;
    case TargetKind::OptimumAngle:
        for (int m : covered) add(c.muscles[m], findOptimumAngle(c.full, m), extrapolateOptimumAngle(c.full, m));
        break;
    case TargetKind::Volume: {
        double v = 0;
        for (int m : covered) v += c.volume[m];
        if (std::isfinite(v)) add(t.muscle, v);   // a model that does not know its volumes is not scored
        break;
    }
    case TargetKind::Share: {
        // Like-for-like with share sources (Kawakami 1994's three add up to 1): the family's flexion
        // torque over that of every muscle a share target names.
        if (sharedMuscles.empty()) break;   // a family of the sources is missing: not comparable
        const int a = indexOf(t.flexionDeg);
        double part = 0, whole = 0;
        for (int m : covered) part += std::max(0.0, c.flexion.points[a][m].torque);
        for (int m : sharedMuscles) whole += std::max(0.0, c.flexion.points[a][m].torque);
        add(t.muscle, whole > 0 ? part / whole : NAN);
        break;
    }
    case TargetKind::Mvc:
    case TargetKind::ForearmMvc:
    case TargetKind::PostureRatio: break;
    }
}

// Every muscle a share target names; none when a family the share targets name has no muscle in the
// model (the sources' shares add up to 1 over all their families: without one they are not comparable).
std::vector<int> findSharedMuscles(const std::vector<std::string>& muscles, const std::vector<AnatomyTarget>& targets) {
    for (const AnatomyTarget& t : targets)
        if (t.kind == TargetKind::Share && findCovered(muscles, t.muscle).empty()) return {};
    std::vector<int> shared;
    for (int i = 0; i < int(muscles.size()); ++i)
        if (std::any_of(targets.begin(), targets.end(), [&](const AnatomyTarget& t) {
                return t.kind == TargetKind::Share && doesFamilyCoverMuscle(t.muscle, muscles[i]);
            }))
            shared.push_back(i);
    return shared;
}

bool isInRange(const AnatomyTarget& t, double minDeg, double maxDeg) {
    return !std::isfinite(t.flexionDeg) || (t.flexionDeg >= minDeg && t.flexionDeg <= maxDeg);
}

}  // namespace

std::vector<TargetScore> scoreAnatomyCurves(const AnatomyCurves& curves, const std::vector<AnatomyTarget>& targets) {
    const std::vector<int> shared = findSharedMuscles(curves.muscles, targets);
    std::vector<TargetScore> out;
    for (const AnatomyTarget& t : targets)
        if (t.kind != TargetKind::ForearmMvc && t.kind != TargetKind::PostureRatio &&
            isInRange(t, curves.minFlexionDeg, curves.maxFlexionDeg))
            scoreCurveTarget(curves, t, shared, out);
    return out;
}

std::vector<TargetScore> scoreAnatomy(const ArmSetup& setup, const std::vector<AnatomyTarget>& targets,
                                      const AnatomySweep& sweep) {
    const AnatomyCurves curves = makeAnatomyCurves(setup, sweep.geometry);
    const std::vector<int> shared = findSharedMuscles(curves.muscles, targets);
    std::vector<TargetScore> out;
    for (const AnatomyTarget& t : targets) {
        if (!isInRange(t, curves.minFlexionDeg, curves.maxFlexionDeg)) continue;
        if (t.kind != TargetKind::ForearmMvc && t.kind != TargetKind::PostureRatio) {
            scoreCurveTarget(curves, t, shared, out);
            continue;
        }
        if (!isScoredForearmTarget(setup, t)) continue;
        const MvcGeometry& g = sweep.byRotation.at(t.rotationDeg);
        const std::size_t a = std::lower_bound(g.flexionDeg.begin(), g.flexionDeg.end(), t.flexionDeg) - g.flexionDeg.begin();
        TargetScore s;
        s.target = t;
        if (t.kind == TargetKind::ForearmMvc) {
            s.value = std::abs(calcSteadyMvcCurve(setup.muscles, g, t.forearmEffort, setup.effort).totalForearmTorque[a]);
        } else {
            const double at = calcSteadyMvcCurve(setup.muscles, g, MuscleGroup::Flexor, setup.effort).totalTorque[a];
            const double ref =
                calcSteadyMvcCurve(setup.muscles, sweep.byRotation.at(0.0), MuscleGroup::Flexor, setup.effort).totalTorque[a];
            s.value = ref > 0 ? at / ref : NAN;
        }
        s.fitValue = s.value;
        s.pass = std::isfinite(s.value) && s.value >= t.lower - t.tolerance && s.value <= t.upper + t.tolerance;
        out.push_back(s);
    }
    return out;
}

std::vector<ScoreSummary> summarizeScores(const std::vector<TargetScore>& scores) {
    std::vector<ScoreSummary> out;
    auto bump = [&](TargetKind k, const std::string& muscle, bool pass) {
        auto it = std::find_if(out.begin(), out.end(), [&](const ScoreSummary& s) { return s.kind == k && s.muscle == muscle; });
        if (it == out.end()) {
            out.push_back({k, muscle});
            it = out.end() - 1;
        }
        ++it->scored;
        it->passed += pass;
    };
    for (const TargetScore& s : scores) {
        bump(s.target.kind, "", s.pass);
        if (s.target.kind == TargetKind::MomentArm || s.target.kind == TargetKind::OptimumAngle) bump(s.target.kind, s.muscle, s.pass);
    }
    return out;
}

}  // namespace armsim
