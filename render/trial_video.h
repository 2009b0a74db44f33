// Videos and stills of arm trials. A recorded trial table (armsim trial / model/trial.h, ending with
// "state_*" columns) is replayed exactly: a MuscleArm of the same subject is built with the table's
// activation trace, and each frame's State is set from one table row with setStateFromTrialRow.
//
// The scene is the arm's own Simbody decorations (upper arm, forearm and hand as shaded solids, the
// elbow, the markers, the strap, and the biceps path line the muscle force element emits, coloured
// blue to red by activation), placed by the replayed state; Simbody's default geometry (body frames)
// is left out. Added as extra geometry: a floor with 10 cm ticks for scale, the force transducer and
// its cable (isometric tables), a hand load, and a force arrow. The biceps line runs inside the upper
// arm's volume in this planar model, so it and the arrow are drawn on top of the solids.
// The default camera is orthographic, on +Z looking at the sagittal (Ground X-Y) plane, +X anterior
// to the right, +Y up; the overlay shows time, elbow angle, activation, forces and live force plots.
#pragma once

#include "basics/table.h"
#include "model/muscle_arm.h"
#include "render/overlay.h"
#include "render/renderer.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace armsim {

/// What each muscle path's colour (blue at 0, red at 1, MuscleForce::calcActivationColor)
/// and, optionally, thickness follow.
enum class MuscleColoring {
    Activation,  ///< the muscle's own decoration: PCSA-weighted active fraction of its motor units
    Force,       ///< muscle force Fse / TrialSceneSettings::forceScale (the primary muscle; others: / own peak)
};

/// Which force the arrow shows.
enum class ForceArrowKind {
    Auto,    ///< Strap for isometric tables (they have a strap_force_N column), else Muscle
    Strap,   ///< transducer reading at the strap, along the flexion direction (needs strap_force_N)
    Muscle,  ///< muscle force on the forearm, from the insertion along the path, beside the line
    None,
};

/// The arm scene besides the camera.
struct TrialSceneSettings {
    MuscleColoring muscleColoring = MuscleColoring::Activation;
    bool thicknessFollows = true;    ///< true: line thickness 3 + 5 x (coloured quantity) px
    double muscleThickness = 4;      ///< line thickness when thicknessFollows is false (px), in (0, 64]
    double forceScale = 0;           ///< force at full red in Force colouring (N), in [0, 1e5]; 0 = table peak
    ForceArrowKind forceArrow = ForceArrowKind::Auto;
    double arrowScale = 0;           ///< arrow length per newton (m/N), in [0, 0.1]; 0 = automatic: a
                                     ///< round 1, 2 or 5 x 10^k N per cm that keeps the table's peak
                                     ///< of the force shown within 15 cm
    bool floor = true;               ///< a floor with 10 cm ticks below the hand's lowest reach
    double handLoad = 0;             ///< mass held in the hand, drawn as a steel ball (kg), >= 0

    /// Throws FieldError naming the field (muscle_thickness, force_scale, arrow_scale, hand_load).
    void validate() const;
};

/// Everything that determines a trial video and still besides the subject and the table.
struct TrialVideoSettings {
    RenderSettings render;           ///< frame size, anti-aliasing, lighting; render.camera is used
                                     ///< only when autoCamera is false
    bool autoCamera = true;          ///< true: calcSagittalCamera for the subject and frame aspect
    double fps = 30;                 ///< video frame rate (1/s), in (0, 240]
    std::string codec = "h264";      ///< "h264" (H.264, .mp4) or "mjpg" (Motion JPEG, .avi)
    double playbackSpeed = 1;        ///< trial seconds per video second (1 = the trial's time scale), > 0
    bool overlay = true;             ///< text panel and live plots
    OverlayStyle overlayStyle;       ///< sizes (font, margin, plots) are for a 720 px high frame and
                                     ///< scale with render.height
    TrialSceneSettings scene;
    std::string videoPath;           ///< video file to write; empty: no video
    std::optional<double> stillTime; ///< trial time of a PNG still (s), within the table; none: no still
    std::string stillPath;           ///< PNG file of the still (required with stillTime)
    std::string tableName;           ///< names the table in error messages (e.g. its CSV path)

    /// Validates every field (FieldError naming it: width, fps, codec, playback_speed, still, ...)
    /// and that something is requested (a video path or a still).
    void validate() const;
};

/// The default camera: orthographic on +Z (lateral) looking at the sagittal plane, +Y up, framing the
/// upper arm, the forearm and hand over the whole elbow range and the floor, for frames of the given
/// aspect (width / height).
Camera calcSagittalCamera(const ArmParameters& arm, double aspect);

/// Renders frames of one recorded trial of one subject. Owns a MuscleArm (one Simbody System) and an
/// OSMesa renderer: use from one thread.
class TrialRenderer {
public:
    /// Checks the table (columns time_s, activation, elbow_angle_deg, elbow_velocity_degps,
    /// muscle_force_N and the muscle's state columns; at least one row; times increasing) and the
    /// settings, then builds the arm. Throws InputError naming the column, row (source line) or field.
    /// The renderer reads the table, which must outlive it (it is not copied).
    TrialRenderer(const ArmSetup& setup, const Table& table, const TrialVideoSettings& settings);
    ~TrialRenderer();
    TrialRenderer(const TrialRenderer&) = delete;
    TrialRenderer& operator=(const TrialRenderer&) = delete;

    /// True for an isometric table (it has a strap_force_N column).
    bool isIsometric() const;
    int getNumRows() const;
    /// Frames of the video: floor((t_end - t_0) fps / playbackSpeed) + 1.
    int getNumFrames() const;
    /// Trial time of frame k: t_0 + k playbackSpeed / fps (s).
    double getFrameTime(int frame) const;
    /// The row whose time is nearest to t (the earlier on a tie); t outside the table gives the
    /// first or last row.
    int findRow(double t) const;

    /// Sets the arm's state from row (realized to Stage::Position) and returns it.
    const SimTK::State& setRow(int row);
    /// The scene at row, then the overlay (if enabled) with the plots up to that row: a
    /// width x height CV_8UC3 BGR image. Deterministic: the same row and settings give the same pixels.
    cv::Mat renderRow(int row);

    /// A Ground box (min, max corners, m) that contains everything the scene draws at any row.
    std::pair<SimTK::Vec3, SimTK::Vec3> calcSceneBox() const;
    const MuscleArm& getModel() const;
    /// The render settings in use (the camera resolved).
    const RenderSettings& getRenderSettings() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// What renderTrialVideo wrote.
struct TrialVideoResult {
    int frames = 0;          ///< video frames written (0: no video)
    std::string videoPath;   ///< empty: no video
    std::string stillPath;   ///< empty: no still
};

/// Renders the video and/or the still that settings request, replaying table for setup. Settings,
/// table and both output paths are checked before anything is written; files are written whole or
/// not at all (the video through VideoWriter, the still with writePng). progress(done, total) is
/// called after each video frame. Throws InputError (FieldError) naming the field, path or column.
TrialVideoResult renderTrialVideo(const ArmSetup& setup, const Table& table, const TrialVideoSettings& settings,
                                  const std::function<void(int, int)>& progress = {});

}  // namespace armsim
