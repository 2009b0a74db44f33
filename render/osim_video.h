// Videos and stills of OpenSim-model trials (model/osim_trial.h tables: an isometric or a free trial of
// one coordinate). Each frame poses the model (model/osim_arm.h) at the row's coordinate value, the
// others at their defaults, and draws the skeleton as bones between the joint centres (the last body
// of a chain reaches twice its centre of mass from its joint), a sphere at every joint, and every
// muscle's path (its wraps included) coloured blue to red by the row's activation_<muscle>; a text
// line gives the time, the coordinate and the mean agonist activation. The camera is orthographic on
// +Z (OpenSim's lateral axis for a right arm), fitted to the skeleton and the paths over the rows.
#pragma once

#include "basics/table.h"
#include "model/osim_file.h"
#include "render/renderer.h"

#include <opencv2/core.hpp>

#include <functional>
#include <optional>
#include <string>

namespace armsim {

struct OsimVideoSettings {
    RenderSettings render;           ///< frame size, anti-aliasing, lighting; the camera is fitted
    double fps = 30;                 ///< video frame rate (1/s), in (0, 240]
    std::string codec = "h264";      ///< "h264" (.mp4) or "mjpg" (.avi)
    double playbackSpeed = 1;        ///< trial seconds per video second, > 0
    bool overlay = true;             ///< the text line
    std::string videoPath;           ///< video file; empty: none
    std::optional<double> stillTime; ///< trial time of a PNG still [s]; none: no still
    std::string stillPath;
    std::string muscleModel;         ///< as the trial's ("" = each muscle's file type): paths do not depend on it
    std::string tableName;           ///< names the table in messages

    /// FieldError naming the field (fps, codec, playback_speed, still), and InputError when nothing
    /// is asked for.
    void validate() const;
};

struct OsimVideoResult {
    int frames = 0;
    std::string videoPath, stillPath;
};

/// One frame of the table at the row nearest to time [s] (within the table; FieldError "still_at"
/// otherwise): the video's frame there, a CV_8UC3 BGR image of settings.render's size.
cv::Mat renderOsimTrialFrame(const OsimModel& model, const Table& table, const OsimVideoSettings& settings, double time);

/// The camera renderOsimTrialVideo uses for this table (settings: the frame size and muscle model).
Camera calcOsimTrialCamera(const OsimModel& model, const Table& table, const OsimVideoSettings& settings);

/// Renders the table (its time_s, <coordinate>_deg and activation_<muscle> columns; InputError naming
/// settings.tableName and the column when one is missing or names no coordinate of the model).
/// progress(done, total) per video frame. Ctrl-C stops between frames (the partial video removed).
OsimVideoResult renderOsimTrialVideo(const OsimModel& model, const Table& table, const OsimVideoSettings& settings,
                                     const std::function<void(int, int)>& progress = {});

}  // namespace armsim
