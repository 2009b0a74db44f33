#include "render/trial_video.h"

#include "basics/bound.h"
#include "basics/errors.h"
#include "model/geometry.h"
#include "model/trial.h"
#include "render/video.h"

#include <fmt/format.h>

#include <algorithm>
#include <set>
#include <cmath>
#include <cstdio>

namespace armsim {

using SimTK::DecorativeGeometry;
using SimTK::Vec3;

namespace {

// Scene geometry (m) and look. Visual only.
constexpr double kLimbRadiusBound = 0.06;    // every arm decoration lies this close to a segment axis
constexpr double kFloorGap = 0.04;           // hand's lowest reach to the floor top
constexpr double kFloorThickness = 0.02;
constexpr double kFloorHalfDepth = 0.12;     // along Z
constexpr double kFloorBehind = 0.15;        // floor extends this far behind the elbow (-X)
constexpr double kFloorAhead = 0.10;         // and this far beyond the hand's reach (+X)
constexpr double kTickSpacing = 0.10;        // scale ticks on the floor
constexpr double kTickHalfWidth = 0.003;
constexpr double kTickHeight = 0.015;
constexpr double kCableLength = 0.12;        // strap to transducer
constexpr double kCableThickness = 2;        // (px)
const Vec3 kTransducerHalf(0.018, 0.03, 0.018);  // transducer body, Y along the cable
constexpr double kPostRadius = 0.008;        // transducer post down to the floor
constexpr double kSteelDensity = 7850;       // hand-load ball (kg/m^3)
constexpr double kArrowOffset = 0.03;        // muscle arrow beside the muscle line
constexpr double kAutoArrowLength = 0.15;    // automatic scale: the peak force's arrow is at most this
constexpr double kArrowThickness = 4;        // (px)
constexpr double kArrowMaxTip = 0.03;        // arrow head length (m), at most 40 % of the arrow
constexpr double kMinArrowLength = 1e-3;     // shorter arrows are not drawn (m)
constexpr double kMuscleThicknessAtZero = 3; // thickness that follows the coloured quantity (px) ...
constexpr double kMuscleThicknessGain = 5;   // ... 3 + 5 x value, as MuscleForce draws it
constexpr double kFramingMargin = 1.12;      // visible height / content height
constexpr double kCameraDistance = 2;        // orthographic camera on +Z (m)
constexpr double kOverlayReferenceHeight = 720;  // overlay sizes are for this frame height (px)
const Vec3 kFloorColor(0.55, 0.60, 0.68);
const Vec3 kTickColor(0.20, 0.22, 0.28);
const Vec3 kTransducerColor(0.25, 0.25, 0.30);
const Vec3 kCableColor(0.15, 0.15, 0.15);
const Vec3 kPostColor(0.50, 0.50, 0.55);
const Vec3 kLoadColor(0.30, 0.30, 0.33);
const Vec3 kArrowColor(0.05, 0.55, 0.20);

const char* const kRequiredColumns[] = {"time_s", "activation", "elbow_angle_deg", "elbow_velocity_degps",
                                        "muscle_force_N"};

double calcReach(const ArmParameters& a) { return a.forearmLength + a.handLength; }
double calcFloorTop(const ArmParameters& a) { return -calcReach(a) - kFloorGap; }

std::string rowName(const Table& t, int row) {
    const int line = t.getSourceLine(row);
    return line > 0 ? "line " + std::to_string(line) : "row " + std::to_string(row + 1);
}

// (t, y) samples of a column, at most ~maxPoints of them, each with its row.
struct Trace {
    std::string title;
    std::vector<double> y;
    std::vector<int> rows;
    std::vector<SimTK::Vec2> samples;
    SimTK::Vec2 yRange;
    SimTK::Vec3 color;
};

Trace makeTrace(const std::string& title, const std::vector<double>& t, const std::vector<double>& y, bool withZero,
                const SimTK::Vec3& color, int maxPoints) {
    Trace tr{title, y, {}, {}, {}, color};
    const int n = int(t.size()), stride = std::max(1, n / std::max(1, maxPoints));
    for (int i = 0; i < n; i += stride) {
        tr.rows.push_back(i);
        tr.samples.emplace_back(t[i], y[i]);
    }
    double lo = *std::min_element(y.begin(), y.end()), hi = *std::max_element(y.begin(), y.end());
    if (withZero) lo = std::min(lo, 0.0), hi = std::max(hi, 0.0);
    const double pad = hi > lo ? 0.05 * (hi - lo) : 1.0;
    tr.yRange = SimTK::Vec2(lo - pad, hi + pad);
    return tr;
}

// The smallest of 1, 2, 5 x 10^k that is >= x (> 0).
double calcNiceStep(double x) {
    const double decade = std::pow(10.0, std::floor(std::log10(x)));
    for (double m : {1.0, 2.0, 5.0})
        if (m * decade >= x * (1 - 1e-12)) return m * decade;
    return 10 * decade;
}

// The style's sizes are for a frame kOverlayReferenceHeight high: scale them to height.
OverlayStyle scaleOverlayStyle(OverlayStyle s, int height) {
    const double k = double(height) / kOverlayReferenceHeight;
    s.fontScale = std::min(4.0, s.fontScale * k);
    s.margin = std::clamp(int(std::lround(s.margin * k)), 0, 400);
    s.plotWidth = std::clamp(int(std::lround(s.plotWidth * k)), 40, 2000);
    s.plotHeight = std::clamp(int(std::lround(s.plotHeight * k)), 30, 2000);
    return s;
}

}  // namespace

void TrialSceneSettings::validate() const {
    checkField("muscle_thickness", muscleThickness, {0, 64, true, false, "px"});
    checkField("force_scale", forceScale, Bound::closed(0, bounds::kMaxIsometricForce.hi, "N, 0 = the table's peak force"));
    // 10 cm per newton draws a 50 N strap force 5 m long, far outside any frame.
    checkField("arrow_scale", arrowScale, Bound::closed(0, 0.1, "m/N, 0 = automatic"));
    checkField("hand_load", handLoad, bounds::kHandLoad);
}

void TrialVideoSettings::validate() const {
    render.validate();
    VideoSettings{fps, render.width, render.height, codec}.validate();
    checkField("playback_speed", playbackSpeed, Bound::positive("trial seconds per video second"));
    overlayStyle.validate();
    scene.validate();
    if (stillTime && !std::isfinite(*stillTime))
        throw FieldError("still_at", "= " + fmt::format("{:g}", *stillTime) + ": expected a finite trial time (s)");
    if (stillTime && stillPath.empty())
        throw FieldError("still", "is empty: expected a .png path for the still at t = " + fmt::format("{:g}", *stillTime) +
                                      " s");
    if (!stillTime && !stillPath.empty())
        throw FieldError("still_at", "is not set: expected the trial time of the still '" + stillPath + "'");
}

Camera calcSagittalCamera(const ArmParameters& arm, double aspect) {
    checkField("aspect", aspect, Bound::positive("width / height"));
    const double x0 = -kFloorBehind, x1 = calcReach(arm) + kFloorAhead;
    const double y0 = calcFloorTop(arm) - kFloorThickness;
    const double y1 = std::max(arm.upperArmLength, arm.originDistance) + kLimbRadiusBound;
    Camera c;
    c.orthographic = true;
    c.lookAt = Vec3(0.5 * (x0 + x1), 0.5 * (y0 + y1), 0);
    c.position = c.lookAt + Vec3(0, 0, kCameraDistance);
    c.up = Vec3(0, 1, 0);
    c.orthoHeight = kFramingMargin * std::max(y1 - y0, (x1 - x0) / aspect);
    c.nearClip = 0.1;
    c.farClip = 2 * kCameraDistance;
    return c;
}

// --------------------------------------------------------------------------------------------------

struct TrialRenderer::Impl {
    ArmSetup setup;
    const Table& table;   // the caller's (not copied: a 1000 Hz trial of ten muscles is ~6 MB)
    TrialVideoSettings settings;
    RenderSettings renderSettings;
    std::unique_ptr<MuscleArm> model;
    SimTK::State state;
    std::unique_ptr<OffscreenRenderer> renderer;
    bool isometric = false;
    ForceArrowKind arrow = ForceArrowKind::None;
    std::vector<double> time, angleDeg, velocityDeg, activation, force, strap, saturated;
    std::vector<std::vector<double>> muscleForce;  // per muscle (empty: the table lacks its column)
    std::vector<double> muscleForceScale;          // per muscle: force at full red (N)
    double forceScale = 1;
    double arrowScale = 1;  // (m/N)
    std::vector<DecorativeGeometry> floor;
    std::vector<Trace> traces;
    std::string title;
    std::string name;  // "trial table" or "trial table '<tableName>'", for messages
    OverlayStyle overlayStyle;  // scaled to the frame height

    Impl(const ArmSetup& s, const Table& t, const TrialVideoSettings& v) : setup(s), table(t), settings(v) {
        settings.validate();
        name = settings.tableName.empty() ? "trial table" : "trial table '" + settings.tableName + "'";
        checkTable();
        const double frames = (time.back() - time.front()) * settings.fps / settings.playbackSpeed;
        if (!settings.videoPath.empty() && table.getNumRows() < 2)
            throw InputError("the " + name + " has one row (t = " + fmt::format("{:g}", time[0]) + " s): a video needs "
                             "two rows or more (one row makes a still: --still-at, --still)");
        if (!settings.videoPath.empty() && !(frames >= 1))
            throw FieldError("playback_speed", "= " + fmt::format("{:g}", settings.playbackSpeed) + ": the " + name +
                                                   " lasts " + fmt::format("{:g}", time.back() - time.front()) +
                                                   " s, less than one frame at " + fmt::format("{:g}", settings.fps) +
                                                   " fps: expected a table lasting at least one frame (a slower playback)");
        if (!settings.videoPath.empty() && !(frames <= 1e6))
            throw FieldError("playback_speed", "= " + fmt::format("{:g}", settings.playbackSpeed) + ": the " + name + " would give " +
                                                   fmt::format("{:g}", frames) + " frames at " + fmt::format("{:g}", settings.fps) +
                                                   " fps: expected at most 1e6 (a faster playback or a lower rate)");
        isometric = table.hasColumn("strap_force_N");
        if (isometric) {
            strap = table.getColumn("strap_force_N");
            if (table.hasColumn("saturated")) saturated = table.getColumn("saturated");
        }
        arrow = settings.scene.forceArrow;
        if (arrow == ForceArrowKind::Auto) arrow = isometric ? ForceArrowKind::Strap : ForceArrowKind::Muscle;
        if (arrow == ForceArrowKind::Strap && !isometric)
            throw InputError("force arrow 'strap': " + name + " has no column 'strap_force_N' (not an isometric "
                             "trial): expected the muscle arrow or none");

        model = std::make_unique<MuscleArm>(setup, readActivationProfiles(setup, table, name));
        state = model->getDefaultState();
        try {
            setRow(0);  // checks the state columns
        } catch (const InputError& e) {
            throw InputError(name + ": " + e.what());
        }

        renderSettings = settings.render;
        if (settings.autoCamera)
            renderSettings.camera =
                calcSagittalCamera(setup.arm, double(renderSettings.width) / renderSettings.height);
        renderer = std::make_unique<OffscreenRenderer>(renderSettings);

        const double peak = *std::max_element(force.begin(), force.end());
        forceScale = settings.scene.forceScale > 0 ? settings.scene.forceScale : (peak > 0 ? peak : 1.0);
        for (int i = 0; i < setup.getNumMuscles(); ++i) {
            const std::string column = setup.getNumMuscles() == 1 ? "muscle_force_N" : "force_" + model->getMuscleName(i) + "_N";
            muscleForce.push_back(table.hasColumn(column) ? table.getColumn(column) : std::vector<double>());
            double musclePeak = 0;
            for (double f : muscleForce.back()) musclePeak = std::max(musclePeak, f);
            // A fixed --force-scale is for the primary muscle; the others keep their own peak.
            muscleForceScale.push_back(i == setup.primary ? forceScale : (musclePeak > 0 ? musclePeak : 1.0));
        }
        arrowScale = settings.scene.arrowScale;
        if (!(arrowScale > 0)) {
            double arrowPeak = 0;
            for (double f : arrow == ForceArrowKind::Strap ? strap : force)
                arrowPeak = std::max(arrowPeak, std::abs(f));
            arrowScale = 0.01 / calcNiceStep(std::max(arrowPeak, 1e-3) * 0.01 / kAutoArrowLength);
        }
        overlayStyle = scaleOverlayStyle(settings.overlayStyle, renderSettings.height);
        if (settings.scene.floor) makeFloor();
        makeTraces();
        title = isometric ? "isometric, " + fmt::format("{:.0f} deg", angleDeg[0]) : "free movement";
    }

    void checkTable() {
        for (const char* c : kRequiredColumns)
            if (!table.hasColumn(c))
                throw InputError(name + " has no column '" + std::string(c) +
                                 "': expected a table written by armsim trial of an armsim model (an OpenSim model's "
                                 "trial table: armsim render TABLE --model FILE.osim)");
        if (table.getNumRows() < 1) throw InputError(name + " has no rows: expected at least one sample");
        time = table.getColumn("time_s");
        angleDeg = table.getColumn("elbow_angle_deg");
        velocityDeg = table.getColumn("elbow_velocity_degps");
        activation = table.getColumn("activation");
        force = table.getColumn("muscle_force_N");
        for (int i = 0; i < table.getNumRows(); ++i) {
            for (const char* c : kRequiredColumns)
                if (!std::isfinite(table.get(i, c)))
                    throw InputError(name + " " + rowName(table, i) + ": column '" + c + "' = " +
                                     fmt::format("{:g}", table.get(i, c)) + ": expected a finite number");
        }
        checkSampleTimes(table, "time_s", settings.tableName.empty() ? "trial table" : settings.tableName);
        checkColumnValues();
    }

    // What a trial writes: every state and transducer cell finite, an elbow angle within the arm's
    // range, a muscle force inside the F0 bound, a saturation flag 0 or 1.
    void checkColumnValues() const {
        const auto bad = [&](int i, const std::string& c, const std::string& expected) {
            return InputError(name + " " + rowName(table, i) + ": column '" + c + "' = " +
                              fmt::format("{:g}", table.get(i, c)) + ": expected " + expected);
        };
        // The arm's elbow range, with room for a free trial pressing into its stop.
        constexpr double kStopSlackDeg = 10;
        const Bound kAngle{setup.arm.minElbowAngleDeg - kStopSlackDeg, setup.arm.maxElbowAngleDeg + kStopSlackDeg, false, false, "deg"};
        const std::string angleExpected = kAngle.describe() + ": the arm's elbow range, " + formatNumber(setup.arm.minElbowAngleDeg) +
                                          ".." + formatNumber(setup.arm.maxElbowAngleDeg) + " deg (included angle), within " +
                                          formatNumber(kStopSlackDeg) + " deg";
        const Bound kForce{-bounds::kMaxIsometricForce.hi, bounds::kMaxIsometricForce.hi, false, false, "N"};
        std::set<std::string> forces = {"muscle_force_N"};
        for (const MuscleSpec& m : setup.muscles) forces.insert("force_" + m.params.name + "_N");
        enum class Rule { None, Finite, Angle, Force, Flag };
        std::vector<Rule> rules;   // per column, found once (a 1e6-row table is checked in a second or so)
        for (const std::string& c : table.getColumnNames())
            rules.push_back(c.rfind("state_", 0) == 0 || c == "strap_force_N" ? Rule::Finite
                            : c == "elbow_angle_deg"                          ? Rule::Angle
                            : forces.count(c) > 0                             ? Rule::Force
                            : c == "saturated"                                ? Rule::Flag
                                                                              : Rule::None);
        for (int i = 0; i < table.getNumRows(); ++i) {
            if (i % 4096 == 0) checkInterruption();
            for (int k = 0; k < table.getNumColumns(); ++k) {
                const double x = table.get(i, k);
                const std::string& c = table.getColumnNames()[k];
                switch (rules[k]) {
                    case Rule::Finite: if (!std::isfinite(x)) throw bad(i, c, "a finite number"); break;
                    case Rule::Angle: if (!kAngle.contains(x)) throw bad(i, c, angleExpected); break;
                    case Rule::Force: if (std::isfinite(x) && !kForce.contains(x)) throw bad(i, c, kForce.describe()); break;
                    case Rule::Flag: if (x != 0 && x != 1) throw bad(i, c, "0 or 1"); break;
                    case Rule::None: break;
                }
            }
        }
    }

    void makeFloor() {
        const ArmParameters& a = setup.arm;
        const double x0 = -kFloorBehind, x1 = calcReach(a) + kFloorAhead, top = calcFloorTop(a);
        floor.push_back(SimTK::DecorativeBrick(Vec3(0.5 * (x1 - x0), 0.5 * kFloorThickness, kFloorHalfDepth))
                            .setTransform(Vec3(0.5 * (x0 + x1), top - 0.5 * kFloorThickness, 0))
                            .setColor(kFloorColor));
        for (double x = std::ceil(x0 / kTickSpacing) * kTickSpacing; x <= x1 - kTickHalfWidth; x += kTickSpacing)
            floor.push_back(SimTK::DecorativeBrick(Vec3(kTickHalfWidth, 0.5 * kTickHeight, kFloorHalfDepth))
                                .setTransform(Vec3(x, top + 0.5 * kTickHeight, 0))
                                .setColor(kTickColor));
    }

    // The force shown is the primary muscle's: name it when there are several.
    std::string getForceLabel() const {
        return setup.getNumMuscles() > 1 ? setup.muscles[setup.primary].params.name + " force" : "muscle force";
    }

    void makeTraces() {
        const int maxPoints = 2 * overlayStyle.plotWidth;
        traces.push_back(makeTrace(getForceLabel() + " (N)", time, force, true, SimTK::Vec3(0.85, 0.25, 0.10), maxPoints));
        if (isometric)
            traces.push_back(makeTrace("transducer (N)", time, strap, true, kArrowColor, maxPoints));
        else
            traces.push_back(makeTrace("elbow angle (deg)", time, angleDeg, false, SimTK::Vec3(0.15, 0.3, 0.8),
                                       maxPoints));
    }

    const SimTK::State& setRow(int row) {
        if (row < 0 || row >= table.getNumRows())
            throw InputError(name + " row " + std::to_string(row) + ": expected a row in [0, " +
                             std::to_string(table.getNumRows() - 1) + "]");
        setStateFromTrialRow(*model, table, row, state);
        model->getSystem().realize(state, SimTK::Stage::Position);
        return state;
    }

    // Ground geometry of one row: the strap point and flexion direction of the state.
    struct Pose {
        Vec3 origin, insertion, strap, hand, flexion;
    };
    Pose calcPose(double q) const {
        const ArmParameters& a = setup.arm;
        const Vec3 along(std::sin(q), -std::cos(q), 0);  // forearm axis, elbow to hand
        return {Vec3(0, a.originDistance, 0), a.insertionDistance * along, a.strapDistance * along,
                a.calcHandComDistance() * along, Vec3(std::cos(q), std::sin(q), 0)};
    }
    double calcLoadRadius() const { return std::cbrt(3 * settings.scene.handLoad / (4 * kPi * kSteelDensity)); }

    // Transducer anchor (top of its body) and bottom.
    static std::pair<Vec3, Vec3> calcTransducer(const Pose& p) {
        const Vec3 anchor = p.strap - kCableLength * p.flexion;
        return {anchor, anchor - 2 * kTransducerHalf[1] * p.flexion};
    }

    // Arrow start and end (Ground) at row, or start == end for none.
    std::pair<Vec3, Vec3> calcArrow(int row, const Pose& p) const {
        const double s = arrowScale;
        if (arrow == ForceArrowKind::Strap) return {p.strap, p.strap + s * strap[row] * p.flexion};
        if (arrow == ForceArrowKind::Muscle) {
            const Vec3 d = (p.origin - p.insertion).normalize();
            Vec3 n(d[1], -d[0], 0);
            if (n[0] < 0) n = -n;  // anterior side of the path
            const Vec3 start = p.insertion + kArrowOffset * n;
            return {start, start + s * force[row] * d};
        }
        return {p.strap, p.strap};
    }

    void appendExtras(int row, std::vector<DecorativeGeometry>& base, SimTK::Array_<DecorativeGeometry>& top) const {
        const Pose p = calcPose(model->getArm().getForearm().getQ(state));
        base.insert(base.end(), floor.begin(), floor.end());
        if (isometric) {
            const auto [anchor, bottom] = calcTransducer(p);
            base.push_back(
                SimTK::DecorativeLine(p.strap, anchor).setColor(kCableColor).setLineThickness(kCableThickness));
            base.push_back(SimTK::DecorativeBrick(kTransducerHalf)
                               .setTransform(SimTK::Transform(SimTK::Rotation(SimTK::UnitVec3(p.flexion), SimTK::YAxis),
                                                              0.5 * (anchor + bottom)))
                               .setColor(kTransducerColor));
            const double floorTop = calcFloorTop(setup.arm);
            if (settings.scene.floor && bottom[1] > floorTop)
                base.push_back(SimTK::DecorativeCylinder(kPostRadius, 0.5 * (bottom[1] - floorTop))
                                   .setTransform(Vec3(bottom[0], 0.5 * (bottom[1] + floorTop), 0))
                                   .setColor(kPostColor));
        }
        if (settings.scene.handLoad > 0)
            base.push_back(SimTK::DecorativeSphere(calcLoadRadius()).setTransform(p.hand).setColor(kLoadColor));
        const auto [start, end] = calcArrow(row, p);
        const double length = (end - start).norm();
        if (length >= kMinArrowLength)
            top.push_back(SimTK::DecorativeArrow(start, end, std::min(kArrowMaxTip, 0.4 * length))
                              .setColor(kArrowColor)
                              .setLineThickness(kArrowThickness));
    }

    // The arm's own decorations: body decorations (the matter subsystem's Topology-stage output,
    // which leaves out Simbody's default frames) and every other subsystem's geometry; every muscle's
    // path on top, coloured as the settings ask.
    void collectDecorations(int row, SimTK::Array_<DecorativeGeometry>& base,
                            SimTK::Array_<DecorativeGeometry>& top) const {
        const SimTK::MultibodySystem& system = model->getSystem();
        const SimTK::SubsystemIndex matter = system.getMatterSubsystem().getMySubsystemIndex();
        // The muscles' own decorations are left out: they are drawn below with the scene's colouring.
        const SimTK::SubsystemIndex forces = model->getMuscleForce(0).getForceSubsystem().getMySubsystemIndex();
        for (SimTK::SubsystemIndex i(0); i < system.getNumSubsystems(); ++i) {
            const SimTK::Subsystem::Guts& guts = system.getSubsystem(i).getSubsystemGuts();
            if (i == matter) guts.calcDecorativeGeometryAndAppend(state, SimTK::Stage::Topology, base);
            else if (i != forces)
                for (SimTK::Stage stage = SimTK::Stage::Topology; stage <= state.getSystemStage(); ++stage)
                    guts.calcDecorativeGeometryAndAppend(state, stage, base);
        }
        // Every muscle on its wrapped path (via points and wrap surfaces drawn with it), on top.
        const TrialSceneSettings& sc = settings.scene;
        for (int m = 0; m < model->getNumMuscles(); ++m) {
            const MuscleForce& f = model->getMuscleForce(m);
            double value = f.calcOutputs(state).activeFraction;
            if (sc.muscleColoring == MuscleColoring::Force && !muscleForce[m].empty())
                value = std::clamp(muscleForce[m][row] / muscleForceScale[m], 0.0, 1.0);
            const double thickness = sc.thicknessFollows ? kMuscleThicknessAtZero + kMuscleThicknessGain * value
                                                         : sc.muscleThickness;
            appendPathDecorations(f.getPath(), f.calcPathGeometry(state, true),
                                  MuscleForce::calcActivationColor(value), thickness, top);
        }
    }

    void drawOverlayAt(int row, cv::Mat& frame) const {
        std::vector<OverlayText> text = {{"trial", title},
                                         {"time", fmt::format("{:.3f} s", time[row])},
                                         {"elbow angle", fmt::format("{:.1f} deg", angleDeg[row])},
                                         {"activation", fmt::format("{:.2f}", activation[row])},
                                         {getForceLabel(), fmt::format("{:.1f} N", force[row])}};
        if (isometric)
            text.push_back({"transducer", fmt::format("{:.1f} N", strap[row]) +
                                              (!saturated.empty() && saturated[row] > 0.5 ? " (saturated)" : "")});
        else
            text.push_back({"elbow velocity", fmt::format("{:.0f} deg/s", velocityDeg[row])});
        if (settings.scene.floor) text.push_back({"floor ticks", "10 cm"});
        if (arrow != ForceArrowKind::None) text.push_back({"arrow", fmt::format("{:.3g} N/cm", 0.01 / arrowScale)});

        std::vector<PlotTrace> plots;
        for (const Trace& tr : traces) {
            PlotTrace p;
            p.title = tr.title;
            p.color = tr.color;
            p.yRange = tr.yRange;
            p.tRange = time.size() > 1 ? SimTK::Vec2(time.front(), time.back()) : SimTK::Vec2(time[0], time[0] + 1);
            const auto end = std::upper_bound(tr.rows.begin(), tr.rows.end(), row);
            p.samples.assign(tr.samples.begin(), tr.samples.begin() + (end - tr.rows.begin()));
            if (p.samples.empty() || tr.rows[end - tr.rows.begin() - 1] != row)
                p.samples.emplace_back(time[row], tr.y[row]);
            plots.push_back(std::move(p));
        }
        drawOverlay(frame, text, plots, overlayStyle);
    }

    cv::Mat renderRow(int row) {
        setRow(row);
        SimTK::Array_<DecorativeGeometry> base, top;
        collectDecorations(row, base, top);
        std::vector<DecorativeGeometry> extras;
        appendExtras(row, extras, top);
        for (auto& g : extras) base.push_back(g);
        cv::Mat frame = renderer->renderLayers(model->getSystem(), state, base, top);
        if (settings.overlay) drawOverlayAt(row, frame);
        return frame;
    }

    std::pair<Vec3, Vec3> calcSceneBox() const {
        const ArmParameters& a = setup.arm;
        const double R = kLimbRadiusBound;
        Vec3 lo(-R, -R, -R), hi(R, std::max(a.upperArmLength, a.originDistance) + R, R);
        auto include = [&](const Vec3& p, double r) {
            for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k] - r), hi[k] = std::max(hi[k], p[k] + r);
        };
        // The forearm and hand over the elbow range and every recorded angle (soft stops overshoot).
        const double qLo = flexionFromElbowAngle(degToRad(a.maxElbowAngleDeg));
        const double qHi = flexionFromElbowAngle(degToRad(a.minElbowAngleDeg));
        constexpr int kAngleSamples = 721;
        for (int i = 0; i < kAngleSamples; ++i) {
            const double q = qLo + (qHi - qLo) * i / (kAngleSamples - 1);
            include(calcReach(a) * Vec3(std::sin(q), -std::cos(q), 0), R);
        }
        const double loadRadius = calcLoadRadius();
        for (int row = 0; row < table.getNumRows(); ++row) {
            const double q = flexionFromElbowAngle(degToRad(angleDeg[row]));
            const Pose p = calcPose(q);
            include(calcReach(a) * Vec3(std::sin(q), -std::cos(q), 0), R);
            include(p.hand, loadRadius);
            if (isometric) {
                const auto [anchor, bottom] = calcTransducer(p);
                include(anchor, kTransducerHalf.norm());
                include(bottom, kTransducerHalf.norm());
            }
            const auto [start, end] = calcArrow(row, p);
            include(start, kArrowMaxTip);
            include(end, kArrowMaxTip);
        }
        if (settings.scene.floor) {
            const double top = calcFloorTop(a);
            include(Vec3(-kFloorBehind, top - kFloorThickness, -kFloorHalfDepth), 0);
            include(Vec3(calcReach(a) + kFloorAhead, top + kTickHeight, kFloorHalfDepth), 0);
        }
        return {lo, hi};
    }
};

TrialRenderer::TrialRenderer(const ArmSetup& setup, const Table& table, const TrialVideoSettings& settings)
    : impl_(std::make_unique<Impl>(setup, table, settings)) {}
TrialRenderer::~TrialRenderer() = default;

bool TrialRenderer::isIsometric() const { return impl_->isometric; }
int TrialRenderer::getNumRows() const { return impl_->table.getNumRows(); }

int TrialRenderer::getNumFrames() const {
    const double duration = impl_->time.back() - impl_->time.front();
    constexpr double kRoundingSlack = 1e-9;  // a duration of exactly k frames gives k + 1 frames
    return int(std::floor(duration * impl_->settings.fps / impl_->settings.playbackSpeed + kRoundingSlack)) + 1;
}

double TrialRenderer::getFrameTime(int frame) const {
    return impl_->time.front() + frame * impl_->settings.playbackSpeed / impl_->settings.fps;
}

int TrialRenderer::findRow(double t) const {
    const std::vector<double>& time = impl_->time;
    const auto it = std::lower_bound(time.begin(), time.end(), t);
    if (it == time.begin()) return 0;
    if (it == time.end()) return int(time.size()) - 1;
    const int i = int(it - time.begin());
    return (time[i] - t < t - time[i - 1]) ? i : i - 1;
}

const SimTK::State& TrialRenderer::setRow(int row) { return impl_->setRow(row); }
cv::Mat TrialRenderer::renderRow(int row) { return impl_->renderRow(row); }
std::pair<Vec3, Vec3> TrialRenderer::calcSceneBox() const { return impl_->calcSceneBox(); }
const MuscleArm& TrialRenderer::getModel() const { return *impl_->model; }
const RenderSettings& TrialRenderer::getRenderSettings() const { return impl_->renderSettings; }

TrialVideoResult renderTrialVideo(const ArmSetup& setup, const Table& table, const TrialVideoSettings& settings,
                                  const std::function<void(int, int)>& progress) {
    settings.validate();
    if (settings.videoPath.empty() && !settings.stillTime)
        throw InputError("trial video: nothing to render: expected a video path or a still time and path");
    TrialRenderer renderer(setup, table, settings);
    const double t0 = table.get(0, "time_s"), t1 = table.get(table.getNumRows() - 1, "time_s");
    if (settings.stillTime) checkField("still_at", *settings.stillTime, Bound::closed(t0, t1, "s, within the trial"));

    TrialVideoResult result;
    result.frames = writeReplay(renderer, settings.videoPath,
                                {settings.fps, settings.render.width, settings.render.height, settings.codec},
                                settings.stillTime, settings.stillPath, progress);
    if (settings.stillTime) result.stillPath = settings.stillPath;
    if (!settings.videoPath.empty()) result.videoPath = settings.videoPath;
    return result;
}

}  // namespace armsim
