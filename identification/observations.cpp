#include "identification/observations.h"

#include "basics/errors.h"
#include "basics/format.h"
#include "basics/table.h"
#include "model/arm_parameters.h"
#include "model/geometry.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

namespace armsim {

int ObservationSet::countDistinctPoints() const {
    std::set<std::pair<double, double>> distinct;
    for (const Observation& o : points) distinct.insert({o.pathLength, o.activation});
    return int(distinct.size());
}

std::string ObservationSet::where(int i) const {
    if (i >= 0 && i < int(points.size()) && points[i].line > 0)
        return source + ":" + std::to_string(points[i].line);
    return source + (i >= 0 ? " (point " + std::to_string(i + 1) + ")" : "");
}

double calcThesisPathLength(double theta) {
    static const ArmParameters thesis;
    return calcBicepsPathLength(thesis.originDistance, thesis.insertionDistance, theta);
}

ObservationSet makeAnglePoints(const std::vector<double>& anglesDeg, const PathFromAngle& pathFromAngle) {
    ObservationSet set;
    for (double deg : anglesDeg) {
        Observation o;
        o.angle = degToRad(deg);
        o.pathLength = pathFromAngle(o.angle);
        set.points.push_back(o);
    }
    return set;
}

void validateObservations(const ObservationSet& set) {
    std::map<std::tuple<int, int, double, double>, int> seen;   // point -> its first row
    for (int i = 0; i < int(set.points.size()); ++i) {
        const Observation& o = set.points[i];
        const std::string at = set.where(i);
        auto fail = [&](const std::string& field, double v, const std::string& expected) {
            throw InputError(at + ": " + field + " = " + formatNumber(v) + ": expected " + expected);
        };
        if (!std::isfinite(o.force) || o.force > 1e5)
            fail("force_N", o.force, "a finite force of at most 1e5 N (100 kN, beyond any muscle)");
        if (o.force < 0) fail("force_N", o.force, ">= 0 (a measured muscle force cannot be negative)");
        if (!std::isfinite(o.pathLength) || !(o.pathLength > 0))
            fail("path length [m]", o.pathLength, "a finite value > 0");
        if (!std::isfinite(o.activation) || o.activation < 0 || o.activation > 1)
            fail("activation", o.activation, "in [0, 1]");
        const auto [first, added] = seen.insert({{o.subject, o.trial, o.pathLength, o.activation}, i});
        if (!added)
            throw InputError(at + ": the same point as " + set.where(first->second) + " (path " +
                             formatNumber(o.pathLength, 10) + " m, activation " + formatNumber(o.activation) + ", trial " +
                             std::to_string(o.trial) + ", subject " + std::to_string(o.subject) +
                             "): expected each point once (give repeated trials a `trial` column, or average them)");
    }
}

ObservationSet readObservations(const std::string& path, const ObservationOptions& options) {
    return makeObservations(Table::readCsv(path), path, options);
}

ObservationSet makeObservations(const Table& t, const std::string& path, const ObservationOptions& options) {
    static const std::set<std::string> known = {"path_m", "path_cm", "angle_deg", "force_N",
                                                "trial", "subject", "activation"};
    for (const std::string& c : t.getColumnNames())
        if (!known.count(c))
            throw InputError(path + ": unknown column '" + c +
                             "': expected path_m | path_cm | angle_deg, force_N, and optionally trial, "
                             "subject, activation");
    const int nPath = t.hasColumn("path_m") + t.hasColumn("path_cm") + t.hasColumn("angle_deg");
    if (nPath != 1)
        throw InputError(path + ": " + std::to_string(nPath) +
                         " position columns: expected exactly one of path_m, path_cm, angle_deg");
    if (!t.hasColumn("force_N")) throw InputError(path + ": missing column 'force_N'");
    if (t.getNumRows() == 0) throw InputError(path + ": no data rows");
    if (t.hasColumn("angle_deg") && !options.pathFromAngle)
        throw InputError(path + ": angle_deg given but no angle-to-path conversion was supplied");

    ObservationSet set;
    set.source = path;
    std::set<int> subjects;   // every subject the file holds, for a --subject it lacks
    for (int r = 0; r < t.getNumRows(); ++r) {
        const std::string at = t.describeRow(path, r);
        auto fail = [&](const std::string& column, double v, const std::string& expected) {
            throw InputError(at + ": column '" + column + "' = " + formatNumber(v) + ": expected " + expected);
        };
        auto integer = [&](const std::string& column) {
            if (!t.hasColumn(column)) return 0;
            const double v = t.get(r, column);
            if (!std::isfinite(v) || v != std::floor(v) || std::abs(v) > 1e9)
                fail(column, v, "an integer");
            return int(v);
        };
        Observation o;
        o.line = t.getSourceLine(r);
        o.trial = integer("trial");
        o.subject = integer("subject");
        subjects.insert(o.subject);
        if (options.subject >= 0 && o.subject != options.subject) continue;
        o.force = t.get(r, "force_N");
        if (!std::isfinite(o.force) || o.force > 1e5)
            fail("force_N", o.force, "a finite force of at most 1e5 N (100 kN, beyond any muscle)");
        if (o.force < 0) fail("force_N", o.force, ">= 0 (a measured muscle force cannot be negative)");
        if (t.hasColumn("activation")) {
            o.activation = t.get(r, "activation");
            if (!std::isfinite(o.activation) || o.activation < 0 || o.activation > 1)
                fail("activation", o.activation, "in [0, 1]");
        }
        if (t.hasColumn("angle_deg")) {
            const double deg = t.get(r, "angle_deg");
            if (!std::isfinite(deg) || !(deg > 0) || deg > 180)
                fail("angle_deg", deg, "in (0, 180] (included elbow angle, 180 = extended)");
            o.angle = degToRad(deg);
            o.pathLength = options.pathFromAngle(o.angle);
            if (!std::isfinite(o.pathLength) || !(o.pathLength > 0))
                fail("angle_deg", deg, "an angle whose path length is > 0 (got " + formatNumber(o.pathLength) + " m)");
        } else {
            const bool cm = t.hasColumn("path_cm");
            const double v = t.get(r, cm ? "path_cm" : "path_m");
            if (!std::isfinite(v) || !(v > 0)) fail(cm ? "path_cm" : "path_m", v, "a finite value > 0");
            o.pathLength = cm ? v * 0.01 : v;
        }
        set.points.push_back(o);
        if (int(set.points.size()) > kMaxForceRows)   // the fit's work and memory grow with the rows squared
            throw InputError(path + ": more than " + std::to_string(kMaxForceRows) + " data rows" +
                             (options.subject >= 0 ? " of subject " + std::to_string(options.subject) : std::string()) +
                             ": expected at most " + std::to_string(kMaxForceRows) + " (one row per effort or per "
                             "averaged point; a force fit of a few unknowns needs tens)");
    }
    if (set.points.empty() && options.subject >= 0) {
        std::string seen;
        for (int k : subjects) seen += (seen.empty() ? "" : ", ") + std::to_string(k);
        throw FieldError("subject", "= " + std::to_string(options.subject) + ": " + path + " has no rows of subject " +
                                        std::to_string(options.subject) + " (" +
                                        (t.hasColumn("subject") ? "its subjects: " + seen : "no 'subject' column: every row is subject 0") +
                                        "): expected one of them");
    }
    // A muscle's maximal force is tens to hundreds of newtons; a file whose every force is under 1 N is
    // in kN (the fit ran to its mass bound and said "not converged").
    constexpr double kLeastMaximalForce = 1;   // N
    const double largest = std::max_element(set.points.begin(), set.points.end(), [](const Observation& a, const Observation& b) {
        return a.force < b.force;
    })->force;
    if (largest > 0 && largest < kLeastMaximalForce)
        throw InputError(path + ": column 'force_N' is at most " + formatNumber(largest) + " N in every row: kN? expected "
                         "newtons (a muscle's maximal force is tens to hundreds of N)");
    if (std::none_of(set.points.begin(), set.points.end(), [](const Observation& o) { return o.force > 0; }))
        throw InputError(path + ": column 'force_N' is 0 N in every row: expected a positive force in one row at "
                                "least (nothing to fit: every mass and tendon length at their bounds would do)");
    validateObservations(set);
    return set;
}

}  // namespace armsim
