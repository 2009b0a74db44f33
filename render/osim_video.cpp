#include "render/osim_video.h"

#include "basics/bound.h"
#include "basics/errors.h"
#include "model/osim_arm.h"
#include "muscles/muscle_force.h"
#include "render/video.h"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace armsim {

using SimTK::DecorativeGeometry;
using SimTK::Vec3;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;
constexpr double kBoneThickness = 10;     // (px)
constexpr double kJointRadius = 0.012;    // (m)
constexpr double kCameraDistance = 2;     // orthographic camera on +Z (m)
constexpr double kFrameMargin = 1.15;     // view height / the scene's
const Vec3 kBoneColor(0.80, 0.76, 0.66);
const Vec3 kJointColor(0.45, 0.45, 0.50);

struct Scene {
    std::vector<std::pair<Vec3, Vec3>> bones;
    std::vector<Vec3> joints;
    std::vector<std::vector<Vec3>> paths;   // per muscle, in Ground
};

// The model posed with coordinate j at angleDeg (the others at their defaults) and what is drawn there.
Scene calcOsimScene(const OsimArm& arm, SimTK::State& state, int j, double angleDeg) {
    arm.setCoordinateValue(state, j, angleDeg * kDeg);
    arm.getSystem().realize(state, SimTK::Stage::Position);
    const SimTK::SimbodyMatterSubsystem& matter = arm.getMatter();
    Scene scene;
    const int n = matter.getNumBodies();
    std::vector<Vec3> joint(n);
    std::vector<int> children(n, 0);
    for (SimTK::MobilizedBodyIndex b(1); b < n; ++b) {
        const SimTK::MobilizedBody& body = matter.getMobilizedBody(b);
        joint[b] = body.getBodyTransform(state) * body.getOutboardFrame(state).p();
        ++children[body.getParentMobilizedBody().getMobilizedBodyIndex()];
    }
    for (SimTK::MobilizedBodyIndex b(1); b < n; ++b) {
        const SimTK::MobilizedBody& body = matter.getMobilizedBody(b);
        const SimTK::MobilizedBodyIndex parent = body.getParentMobilizedBody().getMobilizedBodyIndex();
        if (parent != 0 && (joint[parent] - joint[b]).norm() > 1e-6) scene.bones.emplace_back(joint[parent], joint[b]);
        scene.joints.push_back(joint[b]);
        if (children[b] == 0) {   // a chain's end: its bone reaches twice its centre of mass
            const Vec3 com = body.getBodyTransform(state) * body.getBodyMassCenterStation(state);
            if ((com - joint[b]).norm() > 1e-6) scene.bones.emplace_back(joint[b], joint[b] + 2 * (com - joint[b]));
        }
    }
    for (int i = 0; i < arm.getNumMuscles(); ++i) scene.paths.push_back(arm.getMuscleForce(i).calcPathGeometry(state, true).polyline);
    return scene;
}

// The rows' time_s, <coordinate>_deg (the first that names a coordinate of the model) and the index
// of that coordinate; InputError naming the table otherwise.
int findOsimTableCoordinate(const OsimArm& arm, const Table& table, const std::string& tableName, std::vector<double>& angleDeg) {
    const std::vector<std::string>& names = table.getColumnNames();
    if (names.empty() || names[0] != "time_s" || table.getNumRows() == 0)
        throw InputError(tableName + ": expected an OpenSim-model trial table (time_s first, rows)");
    checkSampleTimes(table, "time_s", tableName);
    for (const std::string& n : names)
        if (n.size() > 4 && n.compare(n.size() - 4, 4, "_deg") == 0) {
            const int j = arm.findCoordinate(n.substr(0, n.size() - 4));
            if (j >= 0) {
                angleDeg = table.getColumn(n);
                return j;
            }
        }
    throw InputError(tableName + ": no <coordinate>_deg column names a coordinate of " + arm.getModel().name +
                     ": expected a table of `armsim trial --model " + arm.getModel().name + "`");
}

// Orthographic on +Z, looking at the middle of everything drawn over the rows (50 of them at most).
Camera fitOsimCamera(const OsimArm& arm, int j, const std::vector<double>& angleDeg, double aspect) {
    SimTK::State state = arm.getDefaultState();
    Vec3 lo(INFINITY), hi(-INFINITY);
    auto include = [&](const Vec3& p) {
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    };
    const int rows = int(angleDeg.size()), step = std::max(1, rows / 50);
    for (int row = 0; row < rows; row += step) {
        const Scene s = calcOsimScene(arm, state, j, angleDeg[row]);
        for (const auto& [a, b] : s.bones) include(a), include(b);
        for (const auto& path : s.paths)
            for (const Vec3& p : path) include(p);
    }
    const Vec3 centre = (lo + hi) / 2;
    Camera c;
    c.orthographic = true;
    c.lookAt = centre;
    c.position = centre + Vec3(0, 0, kCameraDistance);
    c.up = Vec3(0, 1, 0);
    c.orthoHeight = kFrameMargin * std::max({hi[1] - lo[1], (hi[0] - lo[0]) / aspect, 0.05});
    c.nearClip = 0.01;
    c.farClip = 2 * kCameraDistance + (hi[2] - lo[2]);
    return c;
}

class OsimTrialRenderer {
public:
    OsimTrialRenderer(const OsimModel& model, const Table& table, const OsimVideoSettings& settings)
        : arm_(model, {}, settings.muscleModel), table_(table), settings_(settings) {
        findColumns(model);
        state_ = arm_.getDefaultState();
        time_ = table.getColumn("time_s");
        fitCamera();
        renderer_ = std::make_unique<OffscreenRenderer>(render_);
    }

    int findRow(double t) const {
        const auto it = std::lower_bound(time_.begin(), time_.end(), t);
        if (it == time_.begin()) return 0;
        if (it == time_.end()) return int(time_.size()) - 1;
        const int i = int(it - time_.begin());
        return (time_[i] - t < t - time_[i - 1]) ? i : i - 1;
    }

    int getNumFrames() const {
        constexpr double kRoundingSlack = 1e-9;   // a duration of exactly k frames gives k + 1 frames
        return int(std::floor((time_.back() - time_.front()) * settings_.fps / settings_.playbackSpeed + kRoundingSlack)) + 1;
    }
    double getFrameTime(int frame) const { return time_.front() + frame * settings_.playbackSpeed / settings_.fps; }

    cv::Mat renderRow(int row) {
        const Scene scene = calcScene(row);
        SimTK::Array_<DecorativeGeometry> base, top;
        for (const auto& [a, b] : scene.bones)
            base.push_back(SimTK::DecorativeLine(a, b).setColor(kBoneColor).setLineThickness(kBoneThickness));
        for (const Vec3& j : scene.joints)
            base.push_back(SimTK::DecorativeSphere(kJointRadius).setTransform(j).setColor(kJointColor));
        for (std::size_t i = 0; i < scene.paths.size(); ++i) {
            const double a = activation(row, int(i));
            for (std::size_t k = 1; k < scene.paths[i].size(); ++k)
                top.push_back(SimTK::DecorativeLine(scene.paths[i][k - 1], scene.paths[i][k])
                                  .setColor(MuscleForce::calcActivationColor(a))
                                  .setLineThickness(3 + 5 * a));
        }
        cv::Mat frame = renderer_->renderLayers(arm_.getSystem(), state_, base, top);
        if (settings_.overlay) drawText(row, frame);
        return frame;
    }

private:
    void findColumns(const OsimModel& model) {
        (void)model;
        coordinate_ = findOsimTableCoordinate(arm_, table_, settings_.tableName, angle_);
        for (int i = 0; i < arm_.getNumMuscles(); ++i) {
            const int c = table_.findColumn("activation_" + arm_.getMuscleName(i));
            activation_.push_back(c >= 0 ? table_.getColumn(table_.getColumnNames()[c]) : std::vector<double>());
        }
    }

    double activation(int row, int muscle) const {
        const std::vector<double>& a = activation_[muscle];
        return a.empty() ? 0.0 : std::clamp(a[row], 0.0, 1.0);
    }

    Scene calcScene(int row) { return calcOsimScene(arm_, state_, coordinate_, angle_[row]); }

    void fitCamera() {
        render_ = settings_.render;
        render_.camera = fitOsimCamera(arm_, coordinate_, angle_, double(render_.width) / render_.height);
    }

    void drawText(int row, cv::Mat& frame) const {
        double sum = 0;
        int agonists = 0;
        for (std::size_t i = 0; i < activation_.size(); ++i)
            if (!activation_[i].empty() && activation_[i].back() > 0.05) sum += activation(row, int(i)), ++agonists;
        const std::string text = fmt::format("t = {:.3f} s   {} = {:.1f} deg   activation {:.2f}", time_[row],
                                             arm_.getCoordinate(coordinate_).name, angle_[row], agonists ? sum / agonists : 0.0);
        const double scale = 0.6 * render_.height / 720.0;
        cv::putText(frame, text, cv::Point(int(0.02 * render_.width), int(0.05 * render_.height)), cv::FONT_HERSHEY_SIMPLEX,
                    scale, cv::Scalar(20, 20, 20), std::max(1, int(std::lround(2 * scale))), cv::LINE_AA);
    }

    OsimArm arm_;
    const Table& table_;
    const OsimVideoSettings& settings_;
    RenderSettings render_;
    SimTK::State state_;
    std::unique_ptr<OffscreenRenderer> renderer_;
    std::vector<double> time_, angle_;
    std::vector<std::vector<double>> activation_;
    int coordinate_ = -1;
};

}  // namespace

Camera calcOsimTrialCamera(const OsimModel& model, const Table& table, const OsimVideoSettings& settings) {
    const OsimArm arm(model, {}, settings.muscleModel);
    std::vector<double> angleDeg;
    const int j = findOsimTableCoordinate(arm, table, settings.tableName, angleDeg);
    return fitOsimCamera(arm, j, angleDeg, double(settings.render.width) / settings.render.height);
}

cv::Mat renderOsimTrialFrame(const OsimModel& model, const Table& table, const OsimVideoSettings& settings, double time) {
    settings.render.validate();
    OsimTrialRenderer renderer(model, table, settings);
    checkField("still_at", time, Bound::closed(table.get(0, "time_s"), table.get(table.getNumRows() - 1, "time_s"), "s, within the trial"));
    return renderer.renderRow(renderer.findRow(time));
}

void OsimVideoSettings::validate() const {
    render.validate();
    VideoSettings{fps, render.width, render.height, codec}.validate();
    checkField("playback_speed", playbackSpeed, Bound::positive("trial seconds per video second"));
    if (stillTime && !std::isfinite(*stillTime))
        throw FieldError("still_at", "= " + fmt::format("{:g}", *stillTime) + ": expected a finite trial time (s)");
    if (stillTime && stillPath.empty())
        throw FieldError("still", "is empty: expected a .png path for the still at t = " + fmt::format("{:g}", *stillTime) + " s");
    if (videoPath.empty() && !stillTime) throw InputError("osim video: nothing to render: expected a video path or a still");
}

OsimVideoResult renderOsimTrialVideo(const OsimModel& model, const Table& table, const OsimVideoSettings& settings,
                                     const std::function<void(int, int)>& progress) {
    settings.validate();
    OsimTrialRenderer renderer(model, table, settings);
    const double t0 = table.get(0, "time_s"), t1 = table.get(table.getNumRows() - 1, "time_s");
    if (settings.stillTime) checkField("still_at", *settings.stillTime, Bound::closed(t0, t1, "s, within the trial"));
    OsimVideoResult result;
    result.frames = writeReplay(renderer, settings.videoPath,
                                {settings.fps, settings.render.width, settings.render.height, settings.codec},
                                settings.stillTime, settings.stillPath, progress);
    if (settings.stillTime) result.stillPath = settings.stillPath;
    if (!settings.videoPath.empty()) result.videoPath = settings.videoPath;
    return result;
}

}  // namespace armsim
